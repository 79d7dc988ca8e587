/* Binding a ZeroMQ socket to an endpoint as surge's options name it (docs/protocol.md). */
#ifndef SURGE_ENDPOINT_H
#define SURGE_ENDPOINT_H

#include <stddef.h>

enum { SURGE_ENDPOINT_BYTES = 512 };

/* Binds socket to endpoint: "tcp://localhost:PORT" binds 127.0.0.1 (ZeroMQ reads a bind address as an interface
 * name or a numeric address), "tcp://[ADDRESS]:PORT" turns IPv6 on for the socket. bound receives the endpoint
 * bound, with the port the system chose for a wildcard port ("tcp://127.0.0.1:*"). Returns 0, or -1 with err
 * naming the endpoint and ZeroMQ's reason; what names the socket in the message ("publish on", ...). */
int surge_endpoint_bind(void *socket, const char *endpoint, const char *what, char bound[SURGE_ENDPOINT_BYTES],
                        char *err, size_t err_len);

#endif
