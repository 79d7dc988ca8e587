/* A belt surge's numbers (GMD 2025 eq. 21) from one snapshot: the maximal flow height, the mean fluid velocity
 * relative to the belt, the Froude number and the equivalent viscosity, the front, and where the boulders ride.
 * The run writes them to flow.csv every output.flow_interval_s (docs/validation/debris_surge.md). */
#ifndef SURGE_FLOW_METRICS_H
#define SURGE_FLOW_METRICS_H
#include "surge/params.h"
#include "surge/snapshot.h"

typedef struct surge_flow_metrics {
    double time_s;
    double h_max_m;                 /* highest fluid column top (top particle + dp/2), boulders not counted */
    double h_max_with_boulders_m;   /* the same where a disc's top stands higher than the fluid of its column */
    double u_bar_mps;               /* mean fluid x velocity relative to the belt over the surge */
    double froude;                  /* u_bar / sqrt(g h_max) */
    double mu_eq_over_mu0;          /* g sin(theta) h_max^2 / (3 u_bar nu0) */
    double front_from_wall_m;       /* downstream end of the surge: its last column whose top exceeds 10 % of the
                                     * highest, before a gap wider than the kernel support; the other numbers are
                                     * over the fluid (and discs) between the ignored zone and the front */
    double boulders_behind_front_m; /* mean distance of the disc centres behind the front; NaN without discs */
    int fluid_counted;              /* fluid particles measured */
    int boulders_ahead_of_front;    /* discs whose centre is downstream of the front (distances from the wall taken
                                     * around a periodic domain): discs that have left the surge */
} surge_flow_metrics;

/* Over the fluid more than params->output.flow_ignore_m downstream of the upstream wall (walls.upstream_x_m,
 * distances taken around a periodic domain), in columns params->output.flow_column_m wide. The belt speed is the
 * lowest moving wall's x velocity in the snapshot (0 without one). Returns 0, or -1 when no fluid is counted
 * (then the metrics are NaN). */
int surge_flow_metrics_compute(const surge_snapshot *snap, const surge_params *params, surge_flow_metrics *out);
#endif
