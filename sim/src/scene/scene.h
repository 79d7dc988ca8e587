/* Building a scene from its parameters (scene.c): walls, boulders and the fluid block. */
#ifndef SURGE_SCENE_H
#define SURGE_SCENE_H

#include <stddef.h>

#include "surge/params.h"

typedef struct surge_sim surge_sim;

int scene_build(surge_sim *sim, char *err, size_t err_len);

#endif
