/* Hand-off of snapshots from the solver thread to one consumer thread (the publisher, the renderer).
 *
 * A latest-value mailbox over three buffers: the solver fills its own buffer and swaps it in as the latest;
 * the consumer swaps the latest out for its own. The solver holds the lock only for the pointer swap, so it
 * never waits for a slow consumer: a frame the consumer has not taken yet is simply replaced (and counted). */
#ifndef SURGE_MAILBOX_H
#define SURGE_MAILBOX_H

#include <stdint.h>

#include "surge/sim.h"
#include "surge/snapshot.h"

typedef struct surge_frame {
    surge_snapshot snap;       /* particles, in id order */
    surge_diagnostics diag;    /* t, dt, step, energies... */
    surge_params params;       /* the parameters in force at this step (live ones change) */
    surge_derived derived;     /* h, c0, particle counts */
    surge_health_check health; /* SURGE_HEALTHY unless the run is stopping on a failure */
    double wall_s;             /* wall-clock seconds since the run started, when posted */
    uint64_t sequence;         /* 1 for the first frame posted, then +1 per post */
    int final;                 /* the run's last frame */
} surge_frame;

typedef struct surge_mailbox surge_mailbox;

surge_mailbox *surge_mailbox_create(void);
/* Only once neither thread uses it any more. */
void surge_mailbox_destroy(surge_mailbox *mailbox);

/* Solver side, between steps: copies the simulation state into a free buffer and makes it the latest frame.
 * Returns 0, or -1 when out of memory (nothing posted). */
int surge_mailbox_post(surge_mailbox *mailbox, const surge_sim *sim, double wall_s, int final);

/* Consumer side: waits up to timeout_s for a frame newer than the last one taken. Returns NULL on timeout, or
 * once the mailbox is closed and its last frame taken. The frame stays valid until the next take. */
const surge_frame *surge_mailbox_take(surge_mailbox *mailbox, double timeout_s);

/* Solver side: no more posts; wakes the consumer. */
void surge_mailbox_close(surge_mailbox *mailbox);

/* Frames replaced before the consumer took them, and frames posted. */
uint64_t surge_mailbox_superseded(surge_mailbox *mailbox);
uint64_t surge_mailbox_posted(surge_mailbox *mailbox);

#endif
