/* The implicit scheme's state in a checkpoint, after the particles and the boulders (checkpoint.c has the layout):
 * (version 5) the fluid's pressure[f64] by particle id (the next step's p_n) |
 *     (versions 5-8, boulders) the discs' accelerations over the last step and the one before, ax ay ax_n ay_n
 *         [f64 each], and (version 8) their drag stiffness and wetted fraction [f64 each]: the discs' step before
 *         they were solved with the fluid, read and not used |
 * (version 6) the solver's state below (version 7 adds the last step's psi and v* - v_n). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scheme/implicit/implicit.h"

/* The implicit scheme's state beside the particles (checkpoint versions 6 and 7), so that a restarted run repeats the
 * uninterrupted one bit for bit: u32 guesses | phi[f64] by particle id (guesses >= 1) | psi[f64], v*_x - v_x[f64],
 * v*_y - v_y[f64] by particle id (guesses = 2, version 7): the next step's first guesses; guesses = 0 before the first
 * step; then per held multigrid hierarchy i64 built_step | i32 base_iterations | i32 last_iterations | its matrix
 * (amg_write). A version 6 checkpoint (guesses <= 1) restarts psi from 0 and v* from v_n. */
#define ABSURD_GUESS_PA 1e12    /* a guess at phi or psi beyond this is corrupt, as the pressure */
#define ABSURD_GUESS_MPS 1e6    /* and a change of velocity */
static int read_guesses(FILE *f, double *by_id, int count, double absurd)
{
    if (fread(by_id, sizeof *by_id, (size_t)count, f) != (size_t)count)
        return -1;
    for (int i = 0; i < count; i++) /* finite and not absurd */
        if (!(fabs(by_id[i]) < absurd))
            return -1;
    return 0;
}

static int write_solver_state(FILE *f, const surge_sim *sim)
{
    const implicit_work *w = implicit_of(sim);
    const uint32_t guesses = w && w->phi_by_id ? 2 : 0;
    const size_t count = (size_t)sim->count;
    if (fwrite(&guesses, 4, 1, f) != 1 ||
        (guesses && (fwrite(w->phi_by_id, sizeof *w->phi_by_id, count, f) != count ||
                     fwrite(w->psi_by_id, sizeof *w->psi_by_id, count, f) != count ||
                     fwrite(w->dvx_by_id, sizeof *w->dvx_by_id, count, f) != count ||
                     fwrite(w->dvy_by_id, sizeof *w->dvy_by_id, count, f) != count)))
        return -1;
    for (int k = 0; k < 2; k++) {
        const held_multigrid none = {.base_iterations = -1}, *m = w ? &w->multigrid[k] : &none;
        if (fwrite(&m->built_step, 8, 1, f) != 1 || fwrite(&m->base_iterations, 4, 1, f) != 1 ||
            fwrite(&m->last_iterations, 4, 1, f) != 1 || amg_write(m->amg, f) != 0)
            return -1;
    }
    return 0;
}

static int read_solver_state(FILE *f, surge_sim *sim, uint32_t version)
{
    implicit_work *w = implicit_of(sim);
    uint32_t guesses = 0;
    if (fread(&guesses, 4, 1, f) != 1 || guesses > (version >= 7 ? 2u : 1u) || (version >= 7 && guesses == 1))
        return -1;
    double **by_id[] = {&w->phi_by_id, &w->psi_by_id, &w->dvx_by_id, &w->dvy_by_id};
    for (size_t k = 0; k < sizeof by_id / sizeof by_id[0]; k++) /* all of them: a version 6 leaves the others 0 */
        if (!*by_id[k] && !(*by_id[k] = calloc((size_t)sim->count + 1, sizeof **by_id[k])))
            return -1;
    if ((guesses >= 1 && read_guesses(f, w->phi_by_id, sim->count, ABSURD_GUESS_PA) != 0) ||
        (guesses == 2 && (read_guesses(f, w->psi_by_id, sim->count, ABSURD_GUESS_PA) != 0 ||
                          read_guesses(f, w->dvx_by_id, sim->count, ABSURD_GUESS_MPS) != 0 ||
                          read_guesses(f, w->dvy_by_id, sim->count, ABSURD_GUESS_MPS) != 0)))
        return -1;
    for (int k = 0; k < 2; k++) {
        held_multigrid *m = &implicit_of(sim)->multigrid[k];
        char reason[160];
        if (fread(&m->built_step, 8, 1, f) != 1 || fread(&m->base_iterations, 4, 1, f) != 1 ||
            fread(&m->last_iterations, 4, 1, f) != 1 || m->base_iterations < -1 || m->last_iterations < 0 ||
            m->built_step < 0)
            return -1;
        if (!m->amg && !(m->amg = amg_create(reason, sizeof reason, multigrid_blocks(k), sim->params.implicit.multigrid_parts)))
            return -1;
        if (amg_read(m->amg, f, sim->count) != 0)
            return -1;
    }
    return 0;
}

static int write_all(FILE *f, const void *data, size_t len) { return fwrite(data, 1, len, f) == len ? 0 : -1; }
static int read_all(FILE *f, void *data, size_t len) { return fread(data, 1, len, f) == len ? 0 : -1; }

int implicit_checkpoint_write(FILE *f, const surge_sim *sim)
{
    return write_all(f, implicit_of(sim)->pressure_by_id, (size_t)sim->count * sizeof(double)) |
           write_solver_state(f, sim);
}

/* A version 5-8 checkpoint's per-disc block (4 arrays, 6 from version 8): read past */
static int skip_disc_block(FILE *f, int discs, uint32_t version)
{
    const int arrays = version >= 8 ? 6 : 4;
    for (int k = 0; k < arrays * discs; k++) {
        double value;
        if (read_all(f, &value, sizeof value) != 0 || !isfinite(value))
            return -1;
    }
    return 0;
}

/* version: the checkpoint's; before 5 an implicit run restarts from the pressure at rest, not bit for bit (and had
 * no boulders) */
int implicit_checkpoint_read(FILE *f, surge_sim *sim, uint32_t version)
{
    if (version < 5)
        return 0;
    double *pressure_by_id = implicit_of(sim)->pressure_by_id;
    if (read_all(f, pressure_by_id, (size_t)sim->count * sizeof(double)))
        return -1;
    for (int i = 0; i < sim->count; i++) /* outside the state hash: finite and not absurd (1e12 Pa) */
        if (!(fabs(pressure_by_id[i]) < 1e12))
            return -1;
    if (version <= 8 && skip_disc_block(f, sim->boulders.count, version) != 0)
        return -1;
    return version >= 6 ? read_solver_state(f, sim, version) : 0;
}
