/* The live links of a run: replayed journal, control socket, publisher and renderer, served at each step
 * boundary. */
#ifndef SURGE_APP_LIVE_LINKS_H
#define SURGE_APP_LIVE_LINKS_H

#include <signal.h>

#include "cli.h"
#include "surge/control.h"
#include "surge/curve.h"
#include "surge/journal.h"
#include "surge/render.h"

typedef struct live_links {
    void *zmq_context;
    surge_publisher *publisher;
    surge_control *control;
    surge_replay *replay;
    surge_journal *journal;
    surge_renderer *renderer;
    surge_curve_server *curve; /* NULL: the sockets have no security */
    surge_curve_server *numbering; /* without keys: the ZAP handler that numbers the subscribers' connections */
    const char *movie_path; /* NULL: no movie */
    volatile sig_atomic_t *stop_requested; /* set by a stop request on the control socket, and by the signals */
    char replay_error[1024]; /* set when a journal entry could not be replayed */
} live_links;

/* Opens what c asks for; 0, or -1 with the message printed (close_live_links then closes what was opened). */
int open_live_links(const cli *c, const char *outdir, const surge_sim *sim, volatile sig_atomic_t *stop_requested,
                    live_links *l);
/* surge_run's step-boundary callback, user a live_links. */
int at_step_boundary(surge_sim *sim, void *user);
/* Returns -1 when the renderer failed (its message printed). */
int close_live_links(live_links *l, const surge_sim *sim);

#endif
