/* What the canvas draws on the CPU over the OpenGL image: the fluid as a continuous field, and the boulders as
 * solid discs (layers.c). */
#ifndef SURGE_RENDER_LAYERS_H
#define SURGE_RENDER_LAYERS_H

#include <stddef.h>
#include <stdint.h>

/* An RGBA image, top row first, and the rectangle of it drawn into: x in [x0, x1), y in [y0, y1). */
typedef struct surge_layer_target {
    uint8_t *rgba;
    int width;
    int x0, y0, x1, y1;
} surge_layer_target;

/* One fluid particle in pixels, with the value of the field it carries. */
typedef struct surge_splat {
    float x_px, y_px, value;
} surge_splat;

/* Scratch sums of the field on the target's pixels, kept between frames. */
typedef struct surge_field_sums {
    float *weight, *weighted, *solid;
    size_t capacity;
} surge_field_sums;

/* The fluid as a field: at each pixel the Shepard interpolation sum(f W) / sum(W) of the fluid particles' values
 * with the Wendland kernel of smoothing length dp (one pixel at least), coloured through the colour map over
 * [color_min, color_max]. The fluid ends where the kernel sum of fluid and solid particles (walls, boulders: solids,
 * solid_count of them after the fluid's count) falls to half the bulk's, the free surface, and where the solids'
 * sum passes the fluid's, half way to a wall or a boulder: anti-aliased lines. Returns 0, or -1 when out of
 * memory. */
int surge_draw_field(surge_field_sums *sums, const surge_layer_target *t, const surge_splat *splats, int count,
                     int solid_count, double dp_px, int colormap, double color_min, double color_max);

/* A boulder: a solid disc with a thin dark outline and a light spoke from its centre towards its orientation
 * angle_rad (counter-clockwise in the picture), so that its rotation shows. */
void surge_draw_disc(const surge_layer_target *t, double cx_px, double cy_px, double radius_px, double angle_rad);

/* Colours of a boulder (sRGB). */
extern const uint8_t surge_disc_body_rgb[3], surge_disc_outline_rgb[3], surge_disc_spoke_rgb[3];

#endif
