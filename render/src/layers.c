/* The fluid as a continuous field and the boulders as solid discs, drawn on the CPU (see layers.h). */
#include "layers.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "surge/render.h"

const uint8_t surge_disc_body_rgb[3] = {95, 80, 70};    /* dark grey-brown */
const uint8_t surge_disc_outline_rgb[3] = {35, 28, 24}; /* darker still */
const uint8_t surge_disc_spoke_rgb[3] = {235, 235, 235};

/* The quintic Wendland kernel without its constant: (1 - q/2)^4 (2q + 1), q = r/h in [0, 2]. */
static double wendland(double q)
{
    const double t = 1 - 0.5 * q, t2 = t * t;
    return t2 * t2 * (2 * q + 1);
}

/* The kernel sum in the bulk: over a square lattice of spacing dp around a point, averaged over a lattice node and
 * a cell centre (both in pixels). */
static double bulk_sum(double dp_px, double h_px)
{
    if (!(2 * h_px < 64 * dp_px)) /* many particles per kernel: the integral, 4 pi h^2 / 7 over dp^2 */
        return 4 * 3.14159265358979323846 * h_px * h_px / (7 * dp_px * dp_px);
    const int n = (int)ceil(2 * h_px / dp_px) + 1;
    double sum = 0;
    for (int centred = 0; centred < 2; centred++)
        for (int j = -n; j <= n; j++)
            for (int i = -n; i <= n; i++) {
                const double q = hypot(i + 0.5 * centred, j + 0.5 * centred) * dp_px / h_px;
                sum += q < 2 ? wendland(q) : 0;
            }
    return 0.5 * sum;
}

static void blend(uint8_t *px, const uint8_t rgb[3], double alpha)
{
    for (int k = 0; k < 3; k++)
        px[k] = (uint8_t)lround(px[k] + alpha * (rgb[k] - px[k]));
}

/* Adds each particle's kernel weight, and weight times value, to the pixels within its support (a solid's weight
 * to the solids' sum). */
static void splat_sums(surge_field_sums *sums, const surge_layer_target *t, const surge_splat *splats, int count,
                       int solid_count, double h_px)
{
    const int w = t->x1 - t->x0, h = t->y1 - t->y0;
    const double support = 2 * h_px, inv_h = 1 / h_px;
    for (int k = 0; k < count + solid_count; k++) {
        float *weight = k < count ? sums->weight : sums->solid;
        const float value = k < count ? splats[k].value : 0;
        const double x = splats[k].x_px - t->x0, y = splats[k].y_px - t->y0;
        if (!isfinite(x) || !isfinite(y) || x + support < 0 || x - support > w || y + support < 0 || y - support > h)
            continue; /* not on the target: nothing to add, and its pixel range may not fit an int */
        const int i0 = (int)fmax(0, ceil(x - support - 0.5)), i1 = (int)fmin(w - 1, floor(x + support - 0.5));
        const int j0 = (int)fmax(0, ceil(y - support - 0.5)), j1 = (int)fmin(h - 1, floor(y + support - 0.5));
        for (int j = j0; j <= j1; j++) {
            const double dy = j + 0.5 - y;
            for (int i = i0; i <= i1; i++) {
                const double dx = i + 0.5 - x, r2 = dx * dx + dy * dy;
                if (r2 >= support * support)
                    continue;
                const float wk = (float)wendland(sqrt(r2) * inv_h);
                weight[(size_t)j * w + i] += wk;
                sums->weighted[(size_t)j * w + i] += wk * value;
            }
        }
    }
}

/* Scratch sums for n pixels, zeroed; -1 when out of memory. */
static int reset_sums(surge_field_sums *sums, size_t n)
{
    if (n > sums->capacity) {
        float *grown[3] = {sums->weight, sums->weighted, sums->solid};
        for (int k = 0; k < 3; k++) {
            float *g = realloc(grown[k], n * sizeof *g);
            if (!g)
                return -1;
            grown[k] = g;
            *(k == 0 ? &sums->weight : k == 1 ? &sums->weighted : &sums->solid) = g;
        }
        sums->capacity = n;
    }
    memset(sums->weight, 0, n * sizeof *sums->weight);
    memset(sums->weighted, 0, n * sizeof *sums->weighted);
    memset(sums->solid, 0, n * sizeof *sums->solid);
    return 0;
}

/* How much of pixel (i, j) lies where level(a) = sum a - offset is positive: its value over its gradient's
 * length across one pixel, clamped to [0, 1]. */
static double level_coverage(const float *a, const float *b, float sign_b, float offset, int w, int h, int i, int j)
{
    const size_t at = (size_t)j * w + i, right = at + (i + 1 < w), left = at - (i > 0);
    const size_t down = at + (j + 1 < h ? (size_t)w : 0), up = at - (j > 0 ? (size_t)w : 0);
    const double level = a[at] + sign_b * b[at] - offset;
    const double gx = a[right] + sign_b * b[right] - a[left] - sign_b * b[left];
    const double gy = a[down] + sign_b * b[down] - a[up] - sign_b * b[up];
    const double gradient = fmax(0.5 * hypot(gx, gy), 1e-6);
    return fmin(1, fmax(0, 0.5 + level / gradient));
}

int surge_draw_field(surge_field_sums *sums, const surge_layer_target *t, const surge_splat *splats, int count,
                     int solid_count, double dp_px, int colormap, double color_min, double color_max)
{
    const int w = t->x1 - t->x0, h = t->y1 - t->y0;
    if (w <= 0 || h <= 0)
        return 0;
    if (reset_sums(sums, (size_t)w * (size_t)h) != 0)
        return -1;
    const double h_px = fmax(dp_px, 1.0);
    splat_sums(sums, t, splats, count, solid_count, h_px);
    const float half = (float)(0.5 * bulk_sum(dp_px, h_px));
    const float *F = sums->weight, *D = sums->solid;
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            const size_t at = (size_t)j * w + i;
            if (F[at] <= 0)
                continue;
            /* inside the free surface (fluid and solids together), and on the fluid's side of the solids */
            const double coverage = fmin(level_coverage(F, D, 1, half, w, h, i, j),
                                         level_coverage(F, D, -1, 0, w, h, i, j));
            if (coverage <= 0)
                continue;
            uint8_t rgb[3];
            surge_colormap_rgb(colormap, sums->weighted[at] / F[at], color_min, color_max, rgb);
            blend(t->rgba + 4 * ((size_t)(t->y0 + j) * t->width + t->x0 + i), rgb, coverage);
        }
    return 0;
}

static double clamp01(double v) { return v < 0 ? 0 : v > 1 ? 1 : v; }

void surge_draw_disc(const surge_layer_target *t, double cx, double cy, double radius, double angle_rad)
{
    if (!isfinite(cx) || !isfinite(cy) || !isfinite(radius) || cx + radius + 1 < t->x0 || cx - radius - 1 > t->x1 ||
        cy + radius + 1 < t->y0 || cy - radius - 1 > t->y1)
        return; /* not on the target: its pixel range may not fit an int */
    const double outline = fmax(1.0, 0.08 * radius), spoke = fmax(0.6, 0.05 * radius);
    const double ux = cos(angle_rad), uy = -sin(angle_rad); /* the picture's y runs down */
    const int i0 = (int)fmax(t->x0, floor(cx - radius - 1)), i1 = (int)fmin(t->x1 - 1, ceil(cx + radius + 1));
    const int j0 = (int)fmax(t->y0, floor(cy - radius - 1)), j1 = (int)fmin(t->y1 - 1, ceil(cy + radius + 1));
    for (int j = j0; j <= j1; j++)
        for (int i = i0; i <= i1; i++) {
            const double dx = i + 0.5 - cx, dy = j + 0.5 - cy, d = hypot(dx, dy);
            const double coverage = clamp01(radius + 0.5 - d) * fmin(1, 2 * radius);
            if (coverage <= 0)
                continue;
            uint8_t rgb[3];
            memcpy(rgb, surge_disc_body_rgb, 3);
            const double along = dx * ux + dy * uy, across = fabs(dx * uy - dy * ux);
            if (along > 0)
                blend(rgb, surge_disc_spoke_rgb, clamp01(spoke + 0.5 - across) * clamp01(radius - outline - along));
            blend(rgb, surge_disc_outline_rgb, clamp01(d - (radius - outline) + 0.5));
            blend(t->rgba + 4 * ((size_t)j * t->width + i), rgb, coverage);
        }
}
