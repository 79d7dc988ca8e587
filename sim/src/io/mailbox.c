/* Latest-value mailbox over three frame buffers (see surge/mailbox.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/mailbox.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <time.h>

struct surge_mailbox {
    pthread_mutex_t lock;
    pthread_cond_t fresh_or_closed;
    surge_frame frames[3];
    int back;   /* the solver's buffer, filled without the lock */
    int latest; /* the newest complete frame */
    int front;  /* the consumer's buffer */
    int fresh;  /* latest has not been taken */
    int closed;
    uint64_t posted, superseded;
};

surge_mailbox *surge_mailbox_create(void)
{
    surge_mailbox *m = calloc(1, sizeof *m);
    if (!m)
        return NULL;
    pthread_condattr_t attr;
    pthread_condattr_init(&attr);
    pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    pthread_mutex_init(&m->lock, NULL);
    pthread_cond_init(&m->fresh_or_closed, &attr);
    pthread_condattr_destroy(&attr);
    m->back = 0;
    m->latest = 1;
    m->front = 2;
    return m;
}

void surge_mailbox_destroy(surge_mailbox *m)
{
    if (!m)
        return;
    for (int i = 0; i < 3; i++)
        surge_snapshot_free(&m->frames[i].snap);
    pthread_cond_destroy(&m->fresh_or_closed);
    pthread_mutex_destroy(&m->lock);
    free(m);
}

int surge_mailbox_post(surge_mailbox *m, const surge_sim *sim, double wall_s, int final)
{
    surge_frame *f = &m->frames[m->back];
    if (surge_sim_snapshot(sim, &f->snap) != 0)
        return -1;
    f->diag = surge_sim_diagnostics(sim);
    f->params = *surge_sim_params(sim);
    f->derived = *surge_sim_derived(sim);
    f->health = surge_sim_health(sim)->check;
    f->wall_s = wall_s;
    f->final = final;
    pthread_mutex_lock(&m->lock);
    f->sequence = ++m->posted;
    const int swapped = m->latest;
    m->latest = m->back;
    m->back = swapped;
    if (m->fresh)
        m->superseded++;
    m->fresh = 1;
    pthread_cond_signal(&m->fresh_or_closed);
    pthread_mutex_unlock(&m->lock);
    return 0;
}

const surge_frame *surge_mailbox_take(surge_mailbox *m, double timeout_s)
{
    struct timespec deadline;
    clock_gettime(CLOCK_MONOTONIC, &deadline);
    const double whole = floor(timeout_s);
    deadline.tv_sec += (time_t)whole;
    deadline.tv_nsec += (long)((timeout_s - whole) * 1e9);
    if (deadline.tv_nsec >= 1000000000L) {
        deadline.tv_sec++;
        deadline.tv_nsec -= 1000000000L;
    }
    const surge_frame *taken = NULL;
    pthread_mutex_lock(&m->lock);
    while (!m->fresh && !m->closed)
        if (pthread_cond_timedwait(&m->fresh_or_closed, &m->lock, &deadline) == ETIMEDOUT)
            break;
    if (m->fresh) {
        const int swapped = m->front;
        m->front = m->latest;
        m->latest = swapped;
        m->fresh = 0;
        taken = &m->frames[m->front];
    }
    pthread_mutex_unlock(&m->lock);
    return taken;
}

void surge_mailbox_close(surge_mailbox *m)
{
    pthread_mutex_lock(&m->lock);
    m->closed = 1;
    pthread_cond_broadcast(&m->fresh_or_closed);
    pthread_mutex_unlock(&m->lock);
}

uint64_t surge_mailbox_superseded(surge_mailbox *m)
{
    pthread_mutex_lock(&m->lock);
    const uint64_t n = m->superseded;
    pthread_mutex_unlock(&m->lock);
    return n;
}

uint64_t surge_mailbox_posted(surge_mailbox *m)
{
    pthread_mutex_lock(&m->lock);
    const uint64_t n = m->posted;
    pthread_mutex_unlock(&m->lock);
    return n;
}
