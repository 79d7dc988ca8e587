/* The control socket: outside tools read and change parameters, pause, step, save and stop a running
 * simulation (ROUTER socket, JSON requests and replies; docs/protocol.md).
 *
 * Requests are handled in the solver thread at step boundaries, so every change applies atomically between
 * two steps; each applied command is journaled (surge/journal.h). */
#ifndef SURGE_CONTROL_H
#define SURGE_CONTROL_H

#include <signal.h>
#include <stddef.h>

#include "surge/curve.h"
#include "surge/journal.h"
#include "surge/sim.h"

typedef struct surge_control_def {
    const char *endpoint;  /* where the ROUTER socket binds, e.g. "tcp://127.0.0.1:5556" */
    int start_paused;      /* wait for "resume" or "step" before the first step */
    int max_request_bytes; /* a larger request drops the client's connection (ZMQ_MAXMSGSIZE) */
    const surge_curve_server *curve; /* CURVE security with an allow-list of clients; NULL: none (loopback only) */
    int max_peers;         /* connections at once; a new one beyond closes the one quiet longest */
    double idle_peer_s;    /* a connection that sends no request for this long is closed; <= 0: never */
} surge_control_def;

surge_control_def surge_default_control_def(void);

typedef struct surge_control surge_control;

/* Binds the socket; NULL with the reason in err. The journal (may be NULL) records applied commands. */
surge_control *surge_control_start(void *zmq_context, const surge_control_def *def, surge_journal *journal,
                                   char *err, size_t err_len);

/* Solver thread, at a step boundary: answers pending requests while its credit lasts (2 % of the wall time between
 * boundaries, each request spending the time it took), so that a flood of requests cannot hold the solver; the rest
 * wait in order for a later boundary. A reply that finds its client's queue full is kept and sent as the client
 * reads; that client's requests meanwhile are refused "busy", not run. While paused it answers for up to 20 ms,
 * waits up to 0.1 s for a request, and adds SURGE_REQUEST_AGAIN, so the run loop calls again before stepping
 * (unless stop_signal is set). Returns SURGE_CONTINUE or SURGE_REQUEST_* flags (surge/run.h). */
int surge_control_service(surge_control *control, surge_sim *sim, volatile sig_atomic_t *stop_signal);

/* Connections closed so far for going over max_peers, and for idling past idle_peer_s. */
void surge_control_peer_counts(const surge_control *control, long *over_limit, long *idle);

/* The endpoint bound, with the port the system chose for a wildcard one */
const char *surge_control_endpoint(const surge_control *control);

/* How the control socket closed at the run's end */
typedef struct surge_control_end {
    long refused;      /* requests refused after the end: waiting then, or sent until the socket closed */
    long undelivered;  /* replies and refusals still owed when it closed */
    int clients_left;  /* the clients they were owed to */
    int stalled;       /* closed because those clients read nothing for 1 s */
    int time_limit;    /* closed after 5 s, requests still coming or replies still owed */
} surge_control_end;

/* The run has ended: refuses the requests still waiting ("the run has ended"), and those that come until none has
 * for 0.1 s (0.5 s once any has), sending the refusals as the clients read (a client that reads nothing for 1 s is
 * left), for 5 s at most, then closes the socket. Fills end (may be NULL) with how it went. */
void surge_control_close(surge_control *control, surge_control_end *end);

#endif
