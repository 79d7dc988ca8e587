/* The per-particle fields, each declared once: the solver's structure of arrays (struct surge_sim's members), their
 * allocation, the cell sort's permutation, the step-start copies and their roll-back, the state hash and the
 * checkpoint's particle block are all driven by these lists (fields.c). Adding a field is one line here plus its
 * physics. Indices: wall particles [0, wall_count), fluid particles [wall_count, count). */
#ifndef SURGE_FIELDS_H
#define SURGE_FIELDS_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "precision.h"

/* Which particles a field has: every particle, or the wall particles (boulders' included) only */
enum { FIELD_ALL, FIELD_WALLS };

/* What is done with a field besides allocating it: the cell sort permutes it with its particles (else it is
 * recomputed, or indexed by particle id), the state hash and the checkpoint read it over the fluid, in list order */
enum { FIELD_SORTED = 1, FIELD_HASHED = 2, FIELD_CHECKPOINTED = 4 };
#define FIELD_STATE (FIELD_SORTED | FIELD_HASHED | FIELD_CHECKPOINTED)

/* The fluid's state over a step, F(name, type, extent, roles, meaning): each has a copy name_n taken at the step's
 * start (the symplectic scheme's r_n, v_n, rho_n; the roll-back restores it) */
#define SURGE_STEP_FIELDS(F)                                                                                          \
    F(x, double, FIELD_ALL, FIELD_STATE, "position (m); wrapped into the period only at neighbour-list builds")       \
    F(y, double, FIELD_ALL, FIELD_STATE, "position (m)")                                                              \
    F(vx, real, FIELD_ALL, FIELD_STATE, "velocity (m/s); a wall particle's is its wall's")                           \
    F(vy, real, FIELD_ALL, FIELD_STATE, "velocity (m/s)")                                                             \
    F(rho, real, FIELD_ALL, FIELD_STATE, "density (kg/m^3); a wall particle's from its mDBC ghost node")

/* Every other per-particle field, F(name, type, extent, roles, meaning) */
#define SURGE_PARTICLE_FIELDS(F)                                                                                      \
    F(id, int32_t, FIELD_ALL, FIELD_STATE, "the particle's id: its index in snapshots")                              \
    F(kind, uint8_t, FIELD_ALL, 0, "surge_particle_kind, by id")                                                      \
    F(ax, real, FIELD_ALL, 0, "acceleration (m/s^2)")                                                                 \
    F(ay, real, FIELD_ALL, 0, "acceleration (m/s^2)")                                                                 \
    F(drho, real, FIELD_ALL, 0, "density rate (kg/m^3/s)")                                                            \
    F(pressure, real, FIELD_ALL, 0, "pressure (Pa): the Tait equation's, or an incompressible scheme's solve")       \
    F(inv_rho, real, FIELD_ALL, 0, "1 / density")                                                                     \
    F(pair_state, pair_state, FIELD_ALL, 0, "what a fluid neighbour brings to the pair loops, packed (interaction.c)") \
    F(wall_state, wall_pair_state, FIELD_ALL, 0, "what a wall neighbour brings to them, packed (boundary.c)")         \
    F(face_state, wall_face_state, FIELD_ALL, 0, "what a wall neighbour brings to the face search (boundary.c)")      \
    F(visc_speed_mps, real, FIELD_ALL, 0, "max_b |h v_ab.r_ab/(r_ab^2+eta^2)|, a speed (dt_cv)")                       \
    F(face_nx, real, FIELD_ALL, 0, "normal of the nearest wall face within dp (0, 0: none)")                         \
    F(face_ny, real, FIELD_ALL, 0, "")                                                                                \
    F(face_gap_m, real, FIELD_ALL, 0, "the particle's distance from that face (negative past it)")                   \
    F(face_vn_mps, real, FIELD_ALL, 0, "that wall's (or disc's) velocity along the normal")                          \
    F(face_disc, int32_t, FIELD_ALL, 0, "the disc whose face pushes the particle this evaluation (-1: none)")         \
    F(face_push_x, real, FIELD_ALL, 0, "and the push, an acceleration; the disc takes the reaction")                  \
    F(face_push_y, real, FIELD_ALL, 0, "")                                                                            \
    F(grad_c_x, real, FIELD_ALL, 0, "concentration gradient (shifting)")                                              \
    F(grad_c_y, real, FIELD_ALL, 0, "")                                                                               \
    F(surface_nx, real, FIELD_ALL, 0, "near the free surface: the neighbours' grad C averaged, a unit normal")       \
    F(surface_ny, real, FIELD_ALL, 0, "")                                                                             \
    F(grad_rho_x, real, FIELD_ALL, 0, "renormalised density gradient (density diffusion)")                           \
    F(grad_rho_y, real, FIELD_ALL, 0, "")                                                                             \
    F(div_r, real, FIELD_ALL, 0, "div r: 2 in the bulk, less at the free surface")                                    \
    F(kernel_ratio, real, FIELD_ALL, 0, "sum_b m W_ab (fluid and walls) over rho0's lattice sum: above 1 where crowded") \
    F(shift_x, real, FIELD_ALL, 0, "this step's shifting displacement (m)")                                           \
    F(shift_y, real, FIELD_ALL, 0, "")                                                                                \
    F(shift_div, real, FIELD_ALL, 0, "its divergence div(dr), the relative volume change it makes")                   \
    F(surface, int32_t, FIELD_ALL, 0, "free-surface flag of the last predictor pass (int32: the pair loop gathers it)") \
    F(near_surface, uint8_t, FIELD_ALL, 0, "on or next to the free surface")                                          \
    F(wall_of, uint8_t, FIELD_WALLS, FIELD_SORTED, "WALL_*: which wall the particle belongs to")                      \
    F(ghost_dx, real, FIELD_WALLS, FIELD_SORTED, "offset from the wall particle to its mDBC ghost node (m)")          \
    F(ghost_dy, real, FIELD_WALLS, FIELD_SORTED, "")                                                                  \
    F(ghost_fluid_sum, real, FIELD_WALLS, 0, "sum of W V_j of the fluid at the ghost node: ~1 wetted, 0 dry")        \
    F(wall_vx, real, FIELD_WALLS, 0, "no-slip velocity 2 v_wall - v_ghost (viscous term)")                           \
    F(wall_vy, real, FIELD_WALLS, 0, "")                                                                              \
    F(wall_cont_vx, real, FIELD_WALLS, 0, "velocity in the continuity equation: the wall's, plus no penetration")     \
    F(wall_cont_vy, real, FIELD_WALLS, 0, "")                                                                         \
    F(wall_nx, real, FIELD_WALLS, 0, "unit normal from the wall particle toward its ghost (into the fluid)")          \
    F(wall_ny, real, FIELD_WALLS, 0, "")                                                                              \
    F(wall_depth_m, real, FIELD_WALLS, 0, "the wall particle's distance below the wall face (half its ghost offset)")

/* struct surge_sim's members for the lists above */
#define FIELD_MEMBER(name, type, extent, roles, meaning) type *name;
#define FIELD_COPY_MEMBER(name, type, extent, roles, meaning) type *name##_n;

typedef struct surge_sim surge_sim;

/* Every field for count particles, wall_count of them walls (calloc: zero); -1 when out of memory */
int fields_allocate(surge_sim *sim);
void fields_free(surge_sim *sim);

/* array[first + i] = array[order[i]] for i < n, elements of size bytes; scratch holds n doubles */
void fields_gather(void *array, size_t size, const int32_t *order, int first, int n, void *scratch);
/* The sorted fields of particles [first, first + n) in the order order[i] (indices from first; walls: the fields
 * of every extent, fluid: those every particle has); scratch holds n doubles */
void fields_permute(surge_sim *sim, const int32_t *order, int first, int n, void *scratch);

/* The fluid's state back at the step's start (the copies name_n) */
void fields_restore_step_start(surge_sim *sim);

/* The hashed fields over the fluid, in list order, into the FNV-1a hash h */
uint64_t fields_hash(const surge_sim *sim, uint64_t h);

/* The bytes a fluid particle's checkpointed fields take in a checkpoint */
size_t fields_checkpoint_bytes(void);

/* The checkpointed fields over the fluid, in list order; -1 on a write or read error */
int fields_write(FILE *f, const surge_sim *sim);
int fields_read(FILE *f, surge_sim *sim);

/* FNV-1a over len bytes */
uint64_t fields_fnv1a(uint64_t h, const void *data, size_t len);

#endif
