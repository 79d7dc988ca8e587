/* The fluid's rates from its pairs (interaction.c). */
#ifndef SURGE_INTERACTION_H
#define SURGE_INTERACTION_H

#include "precision.h"

typedef struct surge_sim surge_sim;

/* interaction.c (worksharing): before boundary_update, every moving particle's displacement since the build
 * (neighbours_track) and the fluid's pair_state records (which the mDBC ghost nodes read), where the scheme is not
 * incompressible first the fluid's Tait pressure and 1/density; after it, the fluid's rates */
void interaction_prepare(surge_sim *sim);
void interaction_compute(surge_sim *sim, int corrector);
/* What fluid particle a's wall neighbours within 2h say besides the pair terms: whether one is a boulder's, and the
 * nearest fixed wall face within search_m straight below the particle (the wall particle within dp/2 of its normal
 * line), or the nearest face of a disc among them: its distance (search_m when none), normal, the wall's velocity
 * along it, and the wall particle or the disc (-1: none). */
typedef struct wall_face {
    real gap_m, nx, ny, vn_mps;
    int wall, disc;
} wall_face;
wall_face interaction_wall_face(const surge_sim *sim, int a, real search_m, int *near_boulder);
/* The nearest face within search_m of another solid than nearest's: of another disc, or, where nearest is a disc's,
 * of a fixed wall too (a fluid particle in the wedge between a disc and the bed, or between two discs) */
wall_face interaction_other_face(const surge_sim *sim, int a, real search_m, const wall_face *nearest);

#endif
