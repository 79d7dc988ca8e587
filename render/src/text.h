/* Labels drawn with FreeType into an RGBA image (top row first). */
#ifndef SURGE_RENDER_TEXT_H
#define SURGE_RENDER_TEXT_H

#include <stddef.h>
#include <stdint.h>

typedef struct surge_text surge_text;

/* A font at a pixel size suited to an image of that size. NULL with err. */
surge_text *surge_text_open(const char *font_path, int image_width_px, int image_height_px, char *err,
                            size_t err_len);
void surge_text_close(surge_text *text);
int surge_text_size(const surge_text *text); /* pixel size of the font */
/* Draws UTF-8 text with its baseline starting at (x, baseline_y), blended over the image. */
void surge_text_draw(surge_text *text, uint8_t *rgba, int width, int height, int x, int baseline_y, const char *utf8,
                     const uint8_t rgb[3]);

#endif
