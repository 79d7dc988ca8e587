/* A time-stepping scheme: the one interface through which the solver (sim.c, checkpoint.c) steps, saves and restores
 * the state. Each scheme is a folder beside this file that defines one time_scheme; scheme_of picks it from
 * numerics.scheme (registry.c). Shared code asks a scheme for what it needs (its contact distance, its skin, whether it
 * holds the fluid incompressible), never which scheme runs (docs/architecture.md, "Time-stepping schemes"). */
#ifndef SURGE_SCHEME_H
#define SURGE_SCHEME_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "surge/params.h"
#include "surge/sim.h"

typedef struct time_scheme {
    const char *name; /* numerics.scheme's value */
    /* The fluid is held at rho0 by a pressure solve: the scene's rows start dp apart at rho0, the pressure comes from
     * the solve (not the Tait equation), no speed of sound bounds the flow or scales the shift */
    bool incompressible;
    /* The step solves linear systems whose iterations and residuals the diagnostics report */
    bool reports_solves;
    /* The distance from a wall face within which a fluid particle's approach is stopped (in dp) */
    double (*contact_reach_dp)(const surge_params *p);
    /* The share of a squeeze film's exact resistance the scheme resolves by itself, by gap over the kernel's h
     * (boulders/lubrication.h): the films of contacts.lubrication_resolved = measured add the rest */
    const struct lubrication_share *film_share;
    /* The neighbour lists' skin (in h): pairs kept beyond the kernel's support so lists last several steps */
    double (*neighbour_skin_h)(const surge_params *p);
    /* How far ahead of a step's start its force evaluations reach (s), for the neighbour lists' rebuild test */
    double (*lookahead_s)(const surge_sim *sim);
    /* The longest step the scheme takes under parameters p whatever the flow (s): the bounds that follow from the
     * parameters alone (a live change that lowers it past the health check's collapse limit is refused) */
    double (*step_bound_s)(const surge_sim *sim, const surge_params *p);
    /* The scheme's own state beside the particles, after the scene is built (NULL: none); -1 with err set */
    int (*create)(surge_sim *sim, char *err, size_t err_len);
    void (*destroy)(surge_sim *sim);
    /* One step. On failure -1 with sim->health set and the state back at the step's start */
    int (*step)(surge_sim *sim);
    /* Its state in a checkpoint (NULL: none), after the particles and the boulders; -1 on a write or read error or a
     * corrupt block (version: the checkpoint's) */
    int (*checkpoint_write)(FILE *f, const surge_sim *sim);
    int (*checkpoint_read)(FILE *f, surge_sim *sim, uint32_t version);
    /* What `surge check` says of the scene for this scheme (surge_sim_check_report): list_entries per fluid particle
     * and bytes of memory estimated from the lists */
    void (*check_report)(const surge_sim *sim, FILE *out, int verbose, double list_entries, double bytes);
    /* Adds what the scheme knows to the diagnostics (NULL: nothing) */
    void (*diagnostics)(const surge_sim *sim, surge_diagnostics *d);
} time_scheme;

/* The schemes, each in its folder */
extern const time_scheme scheme_explicit;
extern const time_scheme scheme_implicit;

/* The scheme numerics.scheme names */
const time_scheme *scheme_of(const surge_params *p);

/* The share of a film the measured films leave out as resolved: the scheme's own, or the one
 * contacts.lubrication_share names */
const struct lubrication_share *film_share_of(const surge_params *p);

#endif
