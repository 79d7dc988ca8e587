/* Shared inside render/: encoding an RGBA image (top row first) as PNG in memory. */
#ifndef SURGE_RENDER_PNG_ENCODE_H
#define SURGE_RENDER_PNG_ENCODE_H

#include <stddef.h>
#include <stdint.h>

int surge_png_encode_rgba(const uint8_t *rgba, int width, int height, uint8_t **out, size_t *out_len, char *err,
                          size_t err_len);

#endif
