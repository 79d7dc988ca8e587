/* The scene's scales from its parameters alone (scales.c). */
#ifndef SURGE_SCALES_H
#define SURGE_SCALES_H

#include "surge/params.h"

/* The body acceleration in the bed's frame (m/s^2): tilted gravity plus the channel's driving force */
void scene_body_acceleration(const surge_params *p, double *gx_mps2, double *gy_mps2);
/* The largest speed the scene can be expected to reach, from its own scales (docs/method.md) */
double scene_expected_speed(const surge_params *p);
double scene_head_speed(const surge_params *p);
double scene_viscous_speed(const surge_params *p, double speed_mps, double smallest_disc_radius_m);
/* Where the upstream wall's particles end behind it (m): its front layers, then as many layers again with their face
 * turned upstream where the room behind the wall allows. Fluid that comes round a periodic channel (past a caught
 * disc, say) meets a wall there, not the back of the front layers, whose mDBC and face act only downstream. */
double scene_upstream_back_m(const surge_params *p);

#endif
