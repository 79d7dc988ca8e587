/* Running a simulation to its end time with outputs: VTK snapshots and their .pvd collection, the diagnostics
 * CSV, the resolved parameters, checkpoints and progress lines. */
#ifndef SURGE_RUN_H
#define SURGE_RUN_H

#include <signal.h>

#include "surge/sim.h"

typedef struct surge_run_options {
    const char *output_dir;          /* created if missing */
    int threads;                     /* recorded in the outputs */
    int restarted;                   /* continue the collection and CSV of an earlier run in output_dir */
    volatile sig_atomic_t *stop;     /* set asynchronously (SIGINT/SIGTERM) to stop at the next step */
    void (*on_step)(const surge_sim *sim, void *user); /* after every step, in the solver thread */
    void *user;
} surge_run_options;

typedef enum surge_run_result {
    SURGE_RUN_FINISHED = 0,
    SURGE_RUN_UNHEALTHY = 1,   /* the health monitor stopped it; last good state written */
    SURGE_RUN_IO_ERROR = 2,
    SURGE_RUN_INTERRUPTED = 3, /* stopped on request; checkpoint written */
} surge_run_result;

surge_run_options surge_default_run_options(void);
surge_run_result surge_run(surge_sim *sim, const surge_run_options *options, char *err, size_t err_len);

#endif
