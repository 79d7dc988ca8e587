/* A socket's connections capped in number and in idle time (peer_guard.h). */
#define _POSIX_C_SOURCE 200809L
#include "peer_guard.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <zmq.h>

enum { SWEEP_MS = 100 };

/* One accepted connection, known by its descriptor and, since a closed descriptor's number is soon reused, by its
 * two addresses as they were when it was accepted. */
typedef struct peer {
    int fd;
    double last_active_s;
    struct sockaddr_storage local, remote;
    socklen_t local_len, remote_len;
    int closing; /* shut down; waits for ZeroMQ's disconnect event */
} peer;

struct peer_guard {
    void *socket;  /* the watched socket, whose monitor peer_guard_stop ends */
    void *monitor; /* PAIR end of the monitor, used by the guard thread only */
    pthread_t thread;
    pthread_mutex_t lock; /* peers, count: the guard thread and peer_guard_touch */
    peer *peers;
    int count, max_peers;
    double idle_s;
    atomic_int stopping;
    atomic_long over_limit, idle;
};

static double monotonic_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* Shuts the connection down if its descriptor still belongs to it (same local and remote addresses). */
static void close_peer(peer *p)
{
    struct sockaddr_storage local, remote;
    socklen_t local_len = sizeof local, remote_len = sizeof remote;
    if (p->closing)
        return;
    p->closing = 1;
    if (getsockname(p->fd, (struct sockaddr *)&local, &local_len) != 0 || local_len != p->local_len ||
        memcmp(&local, &p->local, local_len) != 0)
        return;
    const int has_remote = getpeername(p->fd, (struct sockaddr *)&remote, &remote_len) == 0;
    if (has_remote != (p->remote_len > 0) ||
        (has_remote && (remote_len != p->remote_len || memcmp(&remote, &p->remote, remote_len) != 0)))
        return;
    shutdown(p->fd, SHUT_RDWR);
}

/* Records a connection's descriptor and addresses. */
static void describe(peer *p, int fd, double now_s)
{
    memset(p, 0, sizeof *p);
    p->fd = fd;
    p->last_active_s = now_s;
    p->local_len = sizeof p->local;
    p->remote_len = sizeof p->remote;
    if (getsockname(fd, (struct sockaddr *)&p->local, &p->local_len) != 0)
        p->local_len = 0;
    if (getpeername(fd, (struct sockaddr *)&p->remote, &p->remote_len) != 0)
        p->remote_len = 0;
}

/* A closed peer keeps its entry until ZeroMQ reports it gone (until then it holds a descriptor), so the table
 * has room for max_peers open and as many closing. */
static void accepted(peer_guard *g, int fd)
{
    pthread_mutex_lock(&g->lock);
    int open = 0, oldest = -1;
    for (int i = 0; i < g->count; i++)
        if (!g->peers[i].closing) {
            open++;
            if (oldest < 0 || g->peers[i].last_active_s < g->peers[oldest].last_active_s)
                oldest = i;
        }
    if (open >= g->max_peers) { /* make room: the peer quiet longest goes */
        close_peer(&g->peers[oldest]);
        atomic_fetch_add(&g->over_limit, 1);
    }
    peer p;
    describe(&p, fd, monotonic_s());
    if (g->count < 2 * g->max_peers) {
        g->peers[g->count++] = p;
    } else { /* every entry is closing: turn the new one away too */
        close_peer(&p);
        atomic_fetch_add(&g->over_limit, 1);
    }
    pthread_mutex_unlock(&g->lock);
}

static void disconnected(peer_guard *g, int fd)
{
    pthread_mutex_lock(&g->lock);
    for (int i = 0; i < g->count; i++)
        if (g->peers[i].fd == fd) {
            g->peers[i] = g->peers[--g->count];
            break;
        }
    pthread_mutex_unlock(&g->lock);
}

static void close_idle(peer_guard *g)
{
    const double now = monotonic_s();
    pthread_mutex_lock(&g->lock);
    for (int i = 0; i < g->count; i++)
        if (!g->peers[i].closing && now - g->peers[i].last_active_s > g->idle_s) {
            close_peer(&g->peers[i]);
            atomic_fetch_add(&g->idle, 1);
        }
    pthread_mutex_unlock(&g->lock);
}

/* Monitor messages: [event: u16, value: u32][endpoint]. */
static void *guard_main(void *arg)
{
    peer_guard *g = arg;
    while (!atomic_load(&g->stopping)) {
        zmq_pollitem_t item = {.socket = g->monitor, .events = ZMQ_POLLIN};
        if (zmq_poll(&item, 1, SWEEP_MS) > 0) {
            zmq_msg_t head, rest;
            zmq_msg_init(&head);
            if (zmq_msg_recv(&head, g->monitor, 0) >= 0) {
                uint16_t event = 0;
                uint32_t value = 0;
                if (zmq_msg_size(&head) >= 6) {
                    memcpy(&event, zmq_msg_data(&head), 2);
                    memcpy(&value, (const char *)zmq_msg_data(&head) + 2, 4);
                }
                while (zmq_msg_more(&head)) { /* the endpoint */
                    zmq_msg_init(&rest);
                    zmq_msg_recv(&rest, g->monitor, 0);
                    const int more = zmq_msg_more(&rest);
                    zmq_msg_close(&rest);
                    if (!more)
                        break;
                }
                if (event == ZMQ_EVENT_ACCEPTED)
                    accepted(g, (int)value);
                else if (event == ZMQ_EVENT_DISCONNECTED)
                    disconnected(g, (int)value);
            }
            zmq_msg_close(&head);
        }
        if (g->idle_s > 0)
            close_idle(g);
    }
    zmq_close(g->monitor);
    return NULL;
}

peer_guard *peer_guard_start(void *context, void *socket, int max_peers, double idle_s, char *err, size_t err_len)
{
    static atomic_int instances;
    char endpoint[64];
    snprintf(endpoint, sizeof endpoint, "inproc://surge-peer-guard-%d", atomic_fetch_add(&instances, 1));
    peer_guard *g = calloc(1, sizeof *g);
    if (!g || max_peers < 1 || !(g->peers = calloc(2 * (size_t)max_peers, sizeof *g->peers))) {
        snprintf(err, err_len, max_peers < 1 ? "the peer limit must be >= 1" : "out of memory");
        free(g);
        return NULL;
    }
    g->socket = socket;
    g->max_peers = max_peers;
    g->idle_s = idle_s;
    pthread_mutex_init(&g->lock, NULL);
    if (zmq_socket_monitor(socket, endpoint, ZMQ_EVENT_ACCEPTED | ZMQ_EVENT_DISCONNECTED) != 0 ||
        !(g->monitor = zmq_socket(context, ZMQ_PAIR)) || zmq_connect(g->monitor, endpoint) != 0 ||
        pthread_create(&g->thread, NULL, guard_main, g) != 0) {
        snprintf(err, err_len, "cannot watch the socket's connections: %s", zmq_strerror(zmq_errno()));
        zmq_socket_monitor(socket, NULL, 0);
        if (g->monitor)
            zmq_close(g->monitor);
        pthread_mutex_destroy(&g->lock);
        free(g->peers);
        free(g);
        return NULL;
    }
    return g;
}

void peer_guard_touch(peer_guard *g, int fd)
{
    if (!g || fd < 0)
        return;
    const double now = monotonic_s();
    pthread_mutex_lock(&g->lock);
    for (int i = 0; i < g->count; i++)
        if (g->peers[i].fd == fd)
            g->peers[i].last_active_s = now;
    pthread_mutex_unlock(&g->lock);
}

void peer_guard_counts(peer_guard *g, long *over_limit, long *idle)
{
    *over_limit = g ? atomic_load(&g->over_limit) : 0;
    *idle = g ? atomic_load(&g->idle) : 0;
}

void peer_guard_stop(peer_guard *g)
{
    if (!g)
        return;
    /* The monitor goes first, while the guard thread still reads its events: ZeroMQ's I/O thread sends an event to
     * a monitor whose reader has gone with a blocking send that never completes, stalling the socket's connections
     * until zmq_ctx_term, which then fails the send and loses the event's frame (a leak) */
    zmq_socket_monitor(g->socket, NULL, 0);
    atomic_store(&g->stopping, 1);
    pthread_join(g->thread, NULL);
    pthread_mutex_destroy(&g->lock);
    free(g->peers);
    free(g);
}
