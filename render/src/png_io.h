/* Shared inside render/: RGBA images (top row first) to PNG in memory, and PNG files back to RGBA. */
#ifndef SURGE_RENDER_PNG_IO_H
#define SURGE_RENDER_PNG_IO_H

#include <stddef.h>
#include <stdint.h>

int surge_png_encode_rgba(const uint8_t *rgba, int width, int height, uint8_t **out, size_t *out_len, char *err,
                          size_t err_len);

/* Reads the PNG file path into rgba (width x height x 4 bytes, alpha 255), which must be that image's size; with
 * rgba NULL only checks that it can be read and has that size. Returns 0, or -1 with err naming the file:
 * unreadable, not a PNG, or another size. */
int surge_png_read_rgba(const char *path, int width, int height, uint8_t *rgba, char *err, size_t err_len);

#endif
