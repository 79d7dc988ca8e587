/* Binding to the endpoints surge's options accept (surge/endpoint.h). */
#include "surge/endpoint.h"

#include <stdio.h>
#include <string.h>
#include <zmq.h>

int surge_endpoint_bind(void *socket, const char *endpoint, const char *what, char bound[SURGE_ENDPOINT_BYTES],
                        char *err, size_t err_len)
{
    static const char localhost[] = "tcp://localhost:";
    char address[SURGE_ENDPOINT_BYTES];
    if (!strncmp(endpoint, localhost, strlen(localhost)))
        snprintf(address, sizeof address, "tcp://127.0.0.1:%s", endpoint + strlen(localhost));
    else
        snprintf(address, sizeof address, "%s", endpoint);
    const int ipv6 = !strncmp(address, "tcp://[", 7);
    size_t bound_len = SURGE_ENDPOINT_BYTES;
    if ((ipv6 && zmq_setsockopt(socket, ZMQ_IPV6, &ipv6, sizeof ipv6) != 0) || zmq_bind(socket, address) != 0 ||
        zmq_getsockopt(socket, ZMQ_LAST_ENDPOINT, bound, &bound_len) != 0) {
        snprintf(err, err_len, "cannot %s '%s': %s", what, endpoint, zmq_strerror(zmq_errno()));
        return -1;
    }
    return 0;
}
