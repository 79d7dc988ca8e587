/* surge keygen: a CURVE key pair for the live links. */
#include "cli.h"

#include <stdio.h>

#include "surge/curve.h"

static const char *usage_keygen =
    "usage: surge keygen NAME\n\n"
    "Makes a CURVE key pair (ZeroMQ's certificate format, as pyzmq's zmq.auth reads it): NAME.key holds the\n"
    "secret key (file mode 0600; keep it private) and NAME.pub the public key to hand to peers. Existing files\n"
    "are never replaced. A run takes its own NAME.key with --curve-key and its clients' .pub files with\n"
    "--curve-clients; a client takes its own .key and the run's .pub (docs/protocol.md).\n";

int command_keygen(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_keygen, stdout);
        return EXIT_OK;
    }
    if (argc != 1 || argv[0][0] == '\0' || argv[0][0] == '-') {
        fprintf(stderr, "surge: keygen needs one NAME (it writes NAME.key and NAME.pub)\n%s", usage_keygen);
        return EXIT_USAGE;
    }
    char err[1024];
    if (surge_curve_write_key_pair(argv[0], err, sizeof err) != 0) {
        fprintf(stderr, "surge: keygen: %s\n", err);
        return EXIT_IO;
    }
    printf("surge: wrote %s.key (secret, mode 0600) and %s.pub (public)\n", argv[0], argv[0]);
    return EXIT_OK;
}
