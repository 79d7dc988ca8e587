/* A belt surge's numbers from a snapshot (see surge/flow_metrics.h; GMD 2025 eq. 21). */
#include "surge/flow_metrics.h"

#include <math.h>
#include <stdlib.h>

/* The distance downstream of the upstream wall, around the period when the domain is periodic. */
static double from_wall(const surge_params *p, double x)
{
    const double d = x - p->walls.upstream_x_m, period = p->domain.length_m;
    return p->domain.periodic_x ? d - period * floor(d / period) : d;
}

int surge_flow_metrics_compute(const surge_snapshot *s, const surge_params *p, surge_flow_metrics *out)
{
    const double nan = NAN, ignore_m = p->output.flow_ignore_m, column_m = p->output.flow_column_m;
    *out = (surge_flow_metrics){s->time_s, nan, nan, nan, nan, nan, nan, nan, 0, 0};
    double belt_mps = 0, belt_y = INFINITY, reach_m = 0;
    for (int32_t i = 0; i < s->count; i++) {
        if (s->kind[i] == SURGE_KIND_MOVING_WALL && s->y_m[i] < belt_y)
            belt_mps = s->vx_mps[i], belt_y = s->y_m[i];
        if (s->kind[i] == SURGE_KIND_FLUID)
            reach_m = fmax(reach_m, from_wall(p, s->x_m[i]));
    }
    const int columns = reach_m > ignore_m ? (int)ceil((reach_m - ignore_m) / column_m) + 1 : 0;
    double *top = columns > 0 ? malloc(sizeof(double) * 2 * (size_t)columns) : NULL;
    if (!top)
        return -1;
    double *top_with_boulders = top + columns;
    for (int c = 0; c < 2 * columns; c++)
        top[c] = -INFINITY;
    for (int32_t i = 0; i < s->count; i++) {
        const double d = s->kind[i] == SURGE_KIND_FLUID ? from_wall(p, s->x_m[i]) : -1;
        if (d > ignore_m) {
            const int c = (int)((d - ignore_m) / column_m);
            top[c] = fmax(top[c], s->y_m[i] + 0.5 * p->numerics.dp_m);
        }
    }
    /* The surge ends at the last column above 10 % of the highest before a gap wider than the kernel support
     * (2h = 2 ch sqrt(2) dp): fluid beyond it, such as a film riding a disc that left the front, is not the surge. */
    double h_all = -INFINITY;
    for (int c = 0; c < columns; c++)
        h_all = fmax(h_all, top[c]);
    const int gap_columns = (int)ceil(2.0 * p->numerics.ch * sqrt(2.0) * p->numerics.dp_m / column_m);
    int last = -1;
    for (int c = 0; c < columns && c - last <= gap_columns; c++)
        if (top[c] > 0.1 * h_all)
            last = c;
    const double front = ignore_m + (last + 1) * column_m;
    double h_max = -INFINITY, h_with = -INFINITY;
    for (int c = 0; c <= last; c++) {
        top_with_boulders[c] = top[c];
        h_max = fmax(h_max, top[c]);
    }
    const surge_boulder_state *b = &s->boulders;
    for (int k = 0; k < b->count; k++) {
        const double d = from_wall(p, b->x_m[k]);
        if (d > ignore_m && d < front) {
            const int c = (int)((d - ignore_m) / column_m);
            top_with_boulders[c] = fmax(top_with_boulders[c], b->y_m[k] + b->radius_m[k]);
        }
    }
    for (int c = 0; c <= last; c++)
        h_with = fmax(h_with, top_with_boulders[c]);
    free(top);
    double sum_u = 0;
    int counted = 0;
    for (int32_t i = 0; i < s->count; i++) {
        const double d = s->kind[i] == SURGE_KIND_FLUID ? from_wall(p, s->x_m[i]) : -1;
        if (d > ignore_m && d < front) {
            sum_u += s->vx_mps[i] - belt_mps;
            counted++;
        }
    }
    if (counted == 0)
        return -1;
    const double g = p->body.gravity_mps2, slope = p->body.slope_deg * 3.14159265358979323846 / 180.0;
    out->h_max_m = h_max;
    out->h_max_with_boulders_m = h_with;
    out->u_bar_mps = sum_u / counted;
    out->froude = out->u_bar_mps / sqrt(g * h_max);
    out->mu_eq_over_mu0 = g * sin(slope) * h_max * h_max / (3.0 * out->u_bar_mps * p->fluid.viscosity_m2ps);
    out->front_from_wall_m = front;
    out->fluid_counted = counted;
    if (b->count > 0) {
        double behind = 0;
        for (int k = 0; k < b->count; k++) {
            const double d = from_wall(p, b->x_m[k]);
            behind += (front - d) / b->count;
            out->boulders_ahead_of_front += d > front;
        }
        out->boulders_behind_front_m = behind;
    }
    return 0;
}
