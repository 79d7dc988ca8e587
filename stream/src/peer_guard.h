/* A bound socket's connections, watched through ZeroMQ's socket monitor in a thread of their own: at most
 * max_peers at once (a new connection beyond that closes the one that has been quiet longest), and a peer that
 * has sent nothing for idle_s is closed. ZeroMQ has no option for either; the monitor reports each accepted
 * connection's descriptor and the guard shuts that descriptor down, which makes ZeroMQ close the connection as
 * if the peer had gone. Neither waits on the thread that uses the socket. */
#ifndef SURGE_PEER_GUARD_H
#define SURGE_PEER_GUARD_H

#include <stddef.h>

typedef struct peer_guard peer_guard;

/* Starts watching socket (call from the thread that owns it, after the bind). idle_s <= 0: no idle limit.
 * NULL with the reason in err. */
peer_guard *peer_guard_start(void *zmq_context, void *socket, int max_peers, double idle_s, char *err,
                             size_t err_len);

/* The connection on descriptor fd (zmq_msg_get(..., ZMQ_SRCFD)) has just sent a message. */
void peer_guard_touch(peer_guard *guard, int fd);

/* Connections closed so far for going over max_peers, and for idling. */
void peer_guard_counts(peer_guard *guard, long *over_limit, long *idle);

/* Stops watching the socket and the thread (call from the thread that owns the socket); the socket's connections
 * stay as they are and it works on unwatched. */
void peer_guard_stop(peer_guard *guard);

#endif
