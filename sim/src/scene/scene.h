/* Building a scene from its parameters (scene.c), and its scales. */
#ifndef SURGE_SCENE_H
#define SURGE_SCENE_H

#include <stddef.h>

#include "surge/params.h"

typedef struct surge_sim surge_sim;

int scene_build(surge_sim *sim, char *err, size_t err_len);
double scene_expected_speed(const surge_params *p);
double scene_head_speed(const surge_params *p);
/* Where the upstream wall's particles end behind it (m): its front layers, then as many layers again with their face
 * turned upstream where the room behind the wall allows. Fluid that comes round a periodic channel (past a caught
 * disc, say) meets a wall there, not the back of the front layers, whose mDBC and face act only downstream. */
double scene_upstream_back_m(const surge_params *p);

#endif
