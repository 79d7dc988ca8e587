/* PNG with libpng: the canvas encoded in memory (fast compression: frames are many), and frame files read back
 * (a restarted run's movie starts with the frames already drawn). */
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "png_io.h"

typedef struct memory_sink {
    uint8_t *data;
    size_t len, capacity;
    int failed;
} memory_sink;

static void sink_write(png_structp png, png_bytep bytes, png_size_t len)
{
    memory_sink *m = png_get_io_ptr(png);
    if (m->failed)
        return;
    if (m->len + len > m->capacity) {
        size_t capacity = m->capacity ? 2 * m->capacity : 1 << 16;
        while (capacity < m->len + len)
            capacity *= 2;
        uint8_t *grown = realloc(m->data, capacity);
        if (!grown) {
            m->failed = 1;
            return;
        }
        m->data = grown;
        m->capacity = capacity;
    }
    memcpy(m->data + m->len, bytes, len);
    m->len += len;
}

static void sink_flush(png_structp png) { (void)png; }

int surge_png_encode_rgba(const uint8_t *rgba, int width, int height, uint8_t **out, size_t *out_len, char *err,
                          size_t err_len)
{
    memory_sink sink = {0};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    png_bytep *rows = malloc((size_t)height * sizeof *rows);
    if (!png || !info || !rows) {
        png_destroy_write_struct(&png, &info);
        free(rows);
        snprintf(err, err_len, "out of memory encoding a PNG");
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        free(rows);
        free(sink.data);
        snprintf(err, err_len, "libpng failed encoding a %d x %d frame", width, height);
        return -1;
    }
    png_set_write_fn(png, &sink, sink_write, sink_flush);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_set_compression_level(png, 1);
    png_write_info(png, info);
    png_set_filler(png, 0, PNG_FILLER_AFTER); /* the RGBA rows lose their alpha byte */
    for (int y = 0; y < height; y++)
        rows[y] = (png_bytep)(rgba + 4 * (size_t)y * (size_t)width);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(rows);
    if (sink.failed) {
        free(sink.data);
        snprintf(err, err_len, "out of memory encoding a PNG");
        return -1;
    }
    *out = sink.data;
    *out_len = sink.len;
    return 0;
}

int surge_png_read_rgba(const char *path, int width, int height, uint8_t *rgba, char *err, size_t err_len)
{
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&image, path)) {
        snprintf(err, err_len, "cannot read the frame '%.900s': %s", path, image.message);
        return -1;
    }
    if ((int)image.width != width || (int)image.height != height) {
        snprintf(err, err_len, "the frame '%.900s' is %u x %u pixels, this run draws %d x %d", path, image.width,
                 image.height, width, height);
        png_image_free(&image);
        return -1;
    }
    if (!rgba) {
        png_image_free(&image);
        return 0;
    }
    image.format = PNG_FORMAT_RGBA;
    if (!png_image_finish_read(&image, NULL, rgba, 0, NULL)) {
        snprintf(err, err_len, "cannot read the frame '%.900s': %s", path, image.message);
        png_image_free(&image);
        return -1;
    }
    return 0;
}
