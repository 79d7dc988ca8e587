/* Building a scene from its parameters (scene.c): walls, boulders and the fluid block. */
#ifndef SURGE_SCENE_H
#define SURGE_SCENE_H

#include <stddef.h>

#include "surge/params.h"

typedef struct surge_sim surge_sim;

int scene_build(surge_sim *sim, char *err, size_t err_len);
/* Packs the fluid around the discs where boulders.pack_fluid asks and scene_build marked it (packing.c; nothing
 * otherwise), with the grid and the neighbour lists set up; 0, or -1 with err */
int scene_pack_fluid(surge_sim *sim, char *err, size_t err_len);

/* The particles the scene of p holds, counted without building it (nothing is allocated): the box's wall particles
 * (the boulders' come on top) and the sites of the initial fluid lattice (the fluid particles, less those the
 * boulders cover). p must be valid (surge_params_validate). 0, or -1 with err. */
int scene_count(const surge_params *p, long long *box_walls, long long *fluid_sites, char *err, size_t err_len);

#endif
