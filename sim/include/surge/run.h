/* Running a simulation to its end time with outputs: VTK snapshots and their .pvd collection, the diagnostics
 * CSV, the resolved parameters, checkpoints and progress lines. */
#ifndef SURGE_RUN_H
#define SURGE_RUN_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>

#include "surge/sim.h"

typedef struct surge_run_options {
    const char *output_dir;          /* created if missing */
    int threads;                     /* recorded in the outputs */
    int restarted;                   /* continue the collection and CSV of an earlier run in output_dir */
    volatile sig_atomic_t *stop;     /* set asynchronously (SIGINT/SIGTERM) to stop at the next step */
    /* Called in the solver thread at every step boundary (once before the first step, then after each step);
     * it may change live parameters. Returns SURGE_CONTINUE or a combination of the requests below. */
    int (*at_step_boundary)(surge_sim *sim, void *user);
    void *user;
} surge_run_options;

enum {
    SURGE_CONTINUE = 0,
    SURGE_REQUEST_SNAPSHOT = 1,   /* write a snapshot of this step now (named by surge_run_snapshot_name) */
    SURGE_REQUEST_CHECKPOINT = 2, /* write checkpoint.bin now */
    SURGE_REQUEST_STOP = 4,       /* end the run here: final snapshot and checkpoint, SURGE_RUN_STOPPED */
    SURGE_REQUEST_AGAIN = 8,      /* call at_step_boundary again before the next step (a paused run) */
};

typedef enum surge_run_result {
    SURGE_RUN_FINISHED = 0,
    SURGE_RUN_UNHEALTHY = 1,   /* the health monitor stopped it; last good state written */
    SURGE_RUN_IO_ERROR = 2,
    SURGE_RUN_INTERRUPTED = 3, /* stopped by a signal; checkpoint written */
    SURGE_RUN_STOPPED = 4,     /* stopped by SURGE_REQUEST_STOP (a control client); checkpoint written */
} surge_run_result;

/* The file name of the snapshot of a step in the output folder ("snap_000001234.vtp"). */
void surge_run_snapshot_name(int64_t step, char *name, size_t len);

surge_run_options surge_default_run_options(void);
surge_run_result surge_run(surge_sim *sim, const surge_run_options *options, char *err, size_t err_len);

#endif
