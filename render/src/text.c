/* Labels with FreeType (see text.h). */
#include "text.h"

#include <ft2build.h>
#include FT_FREETYPE_H
#include <stdio.h>
#include <stdlib.h>

struct surge_text {
    FT_Library library;
    FT_Face face;
    int size_px;
};

surge_text *surge_text_open(const char *font_path, int image_width_px, int image_height_px, char *err, size_t err_len)
{
    surge_text *t = calloc(1, sizeof *t);
    if (!t) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    /* a 36th of the height; in a flat frame (a long, thin scene) up to an 80th of the width, a 12th of the height */
    const int flat = image_width_px / 80 < image_height_px / 12 ? image_width_px / 80 : image_height_px / 12;
    const int size = image_height_px / 36 > flat ? image_height_px / 36 : flat;
    t->size_px = size < 12 ? 12 : size;
    if (FT_Init_FreeType(&t->library) != 0) {
        snprintf(err, err_len, "cannot start FreeType");
        free(t);
        return NULL;
    }
    if (FT_New_Face(t->library, font_path, 0, &t->face) != 0 || FT_Set_Pixel_Sizes(t->face, 0, (FT_UInt)t->size_px) != 0) {
        snprintf(err, err_len, "cannot load the font '%s' (Debian package fonts-dejavu-core)", font_path);
        FT_Done_FreeType(t->library);
        free(t);
        return NULL;
    }
    return t;
}

void surge_text_close(surge_text *t)
{
    if (!t)
        return;
    FT_Done_Face(t->face);
    FT_Done_FreeType(t->library);
    free(t);
}

int surge_text_size(const surge_text *t) { return t->size_px; }

/* The next code point of UTF-8 text (invalid bytes read as themselves). */
static unsigned long next_code_point(const unsigned char **s)
{
    const unsigned char *p = *s;
    unsigned long c = *p++;
    if (c >= 0xc0 && c < 0xe0 && (p[0] & 0xc0) == 0x80)
        c = ((c & 0x1f) << 6) | (*p++ & 0x3f);
    else if (c >= 0xe0 && c < 0xf0 && (p[0] & 0xc0) == 0x80 && (p[1] & 0xc0) == 0x80) {
        c = ((c & 0x0f) << 12) | ((unsigned long)(p[0] & 0x3f) << 6) | (p[1] & 0x3f);
        p += 2;
    }
    *s = p;
    return c;
}

void surge_text_draw(surge_text *t, uint8_t *rgba, int width, int height, int x, int baseline_y, const char *utf8,
                     const uint8_t rgb[3])
{
    const unsigned char *s = (const unsigned char *)utf8;
    while (*s) {
        if (FT_Load_Char(t->face, next_code_point(&s), FT_LOAD_RENDER) != 0)
            continue;
        const FT_GlyphSlot g = t->face->glyph;
        for (unsigned row = 0; row < g->bitmap.rows; row++) {
            const int y = baseline_y - g->bitmap_top + (int)row;
            if (y < 0 || y >= height)
                continue;
            for (unsigned col = 0; col < g->bitmap.width; col++) {
                const int px = x + g->bitmap_left + (int)col;
                if (px < 0 || px >= width)
                    continue;
                const unsigned a = g->bitmap.buffer[row * (unsigned)g->bitmap.pitch + col];
                uint8_t *d = rgba + 4 * ((size_t)y * (size_t)width + (size_t)px);
                for (int k = 0; k < 3; k++)
                    d[k] = (uint8_t)((rgb[k] * a + d[k] * (255 - a) + 127) / 255);
            }
        }
        x += (int)(g->advance.x >> 6);
    }
}
