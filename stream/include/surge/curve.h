/* ZeroMQ's own security for the live links: CURVE encryption with an allow-list of client keys (docs/protocol.md,
 * "Steering from another machine").
 *
 * A key file is ZeroMQ's certificate text (the format czmq and pyzmq's zmq.auth write and read):
 *     curve
 *         public-key = "<40 Z85 characters>"
 *         secret-key = "<40 Z85 characters>"     (only in NAME.key, which stays private)
 * The run holds the server's NAME.key; each client holds its own .key and the server's .pub; the run admits
 * only clients whose .pub lies in its allow-list (a file, or a folder of *.pub files). A ZAP handler
 * (ZeroMQ RFC 27) in its own thread answers the handshakes, so a slow or refused peer never blocks the solver.
 * It gives every connection it admits a number of its own, one more than the last, as its ZAP User-Id (the message
 * property "User-Id"): the publisher tells its subscribers apart by it. A run without keys starts the handler alone
 * (surge_curve_numbering_start) for that. */
#ifndef SURGE_CURVE_H
#define SURGE_CURVE_H
#include <stddef.h>

enum { SURGE_CURVE_KEY_Z85_BYTES = 41 }; /* 40 characters and the terminating zero */

/* Writes NAME.pub (public key) and NAME.key (both keys, mode 0600) from a fresh key pair. Refuses, writing
 * nothing, when either file exists. 0, or -1 with the reason in err. */
int surge_curve_write_key_pair(const char *name, char *err, size_t err_len);

/* Reads a key file. public_z85 receives the public key; secret_z85 (may be NULL) the secret key, which the
 * file must then hold. 0, or -1 naming the file, the line and what is wrong. */
int surge_curve_read_key_file(const char *path, char public_z85[SURGE_CURVE_KEY_Z85_BYTES],
                              char secret_z85[SURGE_CURVE_KEY_Z85_BYTES], char *err, size_t err_len);

/* The security a run's sockets get: the server's secret key and the ZAP handler that checks clients. */
typedef struct surge_curve_server surge_curve_server;

/* Reads the server's key file and the allow-list (a .pub file, or a folder whose *.pub files are read), and
 * starts the ZAP handler on zmq_context. Must come before any socket of that context binds. NULL, with the
 * reason in err, when a file cannot be read or the allow-list holds no key. */
surge_curve_server *surge_curve_server_start(void *zmq_context, const char *server_key_path,
                                             const char *allowed_clients_path, char *err, size_t err_len);

/* The handler alone, without keys: it admits every plain (NULL security) connection of the sockets passed to
 * surge_curve_secure_socket and numbers it. Must come before any socket of that context binds. NULL with err. */
surge_curve_server *surge_curve_numbering_start(void *zmq_context, char *err, size_t err_len);

/* Makes socket (not yet bound) a CURVE server that admits only the allowed clients, or, with a handler started
 * without keys, a plain socket whose connections the handler numbers. 0, or -1 with err. */
int surge_curve_secure_socket(const surge_curve_server *server, void *socket, char *err, size_t err_len);

/* Number of keys admitted, and of handshakes refused so far. */
int surge_curve_allowed_count(const surge_curve_server *server);
long surge_curve_refused_count(const surge_curve_server *server);

/* Stops the ZAP handler; call after the secured sockets are closed. NULL is allowed. */
void surge_curve_server_stop(surge_curve_server *server);
#endif
