/* Publishing the live state over ZeroMQ (PUB/SUB; wire format in docs/protocol.md).
 *
 * The solver thread offers its state at step boundaries; when a subscriber wants it and the cadence allows,
 * the state is copied into a mailbox (surge/mailbox.h) and a publisher thread encodes and sends it. The
 * solver never waits for the network: the mailbox keeps only the latest frame and the PUB socket drops
 * messages for a subscriber whose queue holds send_hwm messages. */
#ifndef SURGE_PUBLISHER_H
#define SURGE_PUBLISHER_H

#include <stddef.h>
#include <stdint.h>

#include "surge/curve.h"
#include "surge/sim.h"

typedef struct surge_publisher_def {
    const char *endpoint; /* where the PUB socket binds, e.g. "tcp://127.0.0.1:5555" */
    int every_steps;      /* publish at most once every this many steps */
    double max_rate_hz;   /* and at most this many times per wall-clock second; 0: no limit */
    int send_hwm;         /* messages queued per subscriber before the newest are dropped (ZMQ_SNDHWM) */
    const surge_curve_server *curve; /* CURVE security with an allow-list of subscribers, or the handler that only
                                        numbers connections (surge_curve_numbering_start); NULL: none */
    int max_peers;        /* subscribers connected at once; a new one beyond closes the one connected longest */
} surge_publisher_def;

surge_publisher_def surge_default_publisher_def(void);

typedef struct surge_publisher surge_publisher;

typedef struct surge_publisher_report {
    uint64_t frames_posted;     /* states handed from the solver thread to the publisher */
    uint64_t frames_superseded; /* replaced by a newer one before the publisher took them */
    uint64_t messages_sent;     /* state, bodies and stats messages given to the PUB socket */
    uint64_t bytes_sent;
    long peers_over_limit;      /* subscribers' connections closed to stay within max_peers */
} surge_publisher_report;

/* Binds the socket and starts the publisher thread; NULL with the reason in err. */
surge_publisher *surge_publisher_start(void *zmq_context, const surge_publisher_def *def, char *err,
                                       size_t err_len);

/* The endpoint bound, with the port the system chose for a wildcard one */
const char *surge_publisher_endpoint(const surge_publisher *publisher);

/* Solver thread, at a step boundary: posts the state when a subscriber wants one and the cadence allows. */
void surge_publisher_offer(surge_publisher *publisher, const surge_sim *sim);

/* Any thread (the renderer's): hands a rendered frame (PNG bytes, copied) to the publisher, which sends the
 * newest one on topic "frame" to subscribers of that topic. */
void surge_publisher_post_png(surge_publisher *publisher, const uint8_t *png, size_t png_len, int64_t step,
                              double time_s);

/* Solver thread, once the run has ended: posts the final state (status "final" in stats) whatever the
 * cadence, lets the thread send it, stops it and closes the socket. report may be NULL. */
void surge_publisher_finish(surge_publisher *publisher, const surge_sim *sim, surge_publisher_report *report);

#endif
