/* The command line's options: parsing, checking their values and the combinations they may be given in. */
#include "cli.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int wants_help(int argc, char **argv)
{
    for (int i = 0; i < argc; i++)
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h"))
            return 1;
    return 0;
}

static int parse_int(const char *text, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno || v < lo || v > hi)
        return -1;
    *out = (int)v;
    return 0;
}

static int parse_real(const char *text, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno || !(v >= lo && v <= hi))
        return -1;
    *out = v;
    return 0;
}

/* A ZeroMQ endpoint, or a bare port meaning loopback; *remote tells whether other machines can reach it. */
static int parse_endpoint(const char *option, const char *text, char *out, int *remote)
{
    int port;
    *remote = 0;
    if (parse_int(text, 1, 65535, &port) == 0) {
        snprintf(out, ENDPOINT_BYTES, "tcp://127.0.0.1:%d", port);
        return 0;
    }
    if (strlen(text) >= ENDPOINT_BYTES || !strstr(text, "://")) {
        fprintf(stderr, "surge: %s needs an endpoint such as tcp://127.0.0.1:5555 or ipc:///tmp/surge, or a port; "
                        "got '%s'\n", option, text);
        return -1;
    }
    snprintf(out, ENDPOINT_BYTES, "%s", text);
    /* this machine only: a local socket file, or TCP on loopback; any other transport (tcp elsewhere, pgm, epgm,
     * norm, udp, ws...) can be reached from other machines */
    *remote = !(!strncmp(text, "ipc://", 6) || !strncmp(text, "inproc://", 9) || !strncmp(text, "tcp://127.", 10) ||
                !strncmp(text, "tcp://localhost:", 16) || !strncmp(text, "tcp://[::1]:", 12));
    return 0;
}

/* Who may reach the sockets: with CURVE keys, only the allowed clients, from anywhere; without, whoever can
 * reach the endpoint, so nobody elsewhere may steer a run and a remote publisher is warned about. */
static int check_endpoint_security(const cli *c)
{
    if (!c->curve_key_path != !c->curve_clients_path) {
        fprintf(stderr, "surge: %s needs %s too: the run's secret key and the allowed clients' public keys go "
                        "together (docs/protocol.md, \"Steering from another machine\")\n",
                c->curve_key_path ? "--curve-key" : "--curve-clients",
                c->curve_key_path ? "--curve-clients" : "--curve-key");
        return -1;
    }
    if (c->curve_key_path && !c->publish[0] && !c->control[0]) {
        fprintf(stderr, "surge: --curve-key secures --publish and --control; neither is given\n");
        return -1;
    }
    if (c->curve_key_path)
        return 0;
    if (c->control_remote) {
        fprintf(stderr, "surge: --control %s can be reached from other machines and has no authentication: refused. "
                        "Give it CURVE keys (--curve-key and --curve-clients; `surge keygen` makes them), or bind it to "
                        "loopback (a bare port does) and reach it through an SSH tunnel (docs/protocol.md)\n",
                c->control);
        return -1;
    }
    if (c->publish_remote)
        fprintf(stderr, "surge: warning: --publish %s is not bound to loopback and has no authentication, so anyone "
                        "who can reach it can read the state; --curve-key and --curve-clients admit only the clients "
                        "you name (docs/protocol.md)\n", c->publish);
    return 0;
}

/* Each option parser below returns 1 when a is its option (*i then past the value it took), 0 when a is not, and
 * -1 with the message printed when the value is missing or wrong. value: the next argument, NULL at the end. */

static const char *take_value(const char *value, int *i)
{
    ++*i;
    return value;
}

/* -s section.key=value, --set section.key=value */
static int parse_override(const char *a, const char *value, int *i, cli *c)
{
    if (strcmp(a, "-s") && strcmp(a, "--set"))
        return 0;
    if (!value) {
        fprintf(stderr, "surge: %s needs section.key=value\n", a);
        return -1;
    }
    if (c->override_count == (int)(sizeof c->overrides / sizeof c->overrides[0])) {
        fprintf(stderr, "surge: too many -s overrides (at most 256)\n");
        return -1;
    }
    c->overrides[c->override_count++] = take_value(value, i);
    return 1;
}

/* What a run reads and writes: -o, --threads, --restart, --replay, --frames, --movie, --font, --overwrite */
static int parse_output_option(const char *a, const char *value, int *i, cli *c)
{
    if (!strcmp(a, "-o")) {
        if (!value || value[0] == '\0') {
            fprintf(stderr, "surge: -o needs an output folder\n");
            return -1;
        }
        c->output_dir = take_value(value, i);
    } else if (!strcmp(a, "--threads")) {
        if (!value || parse_int(value, 1, 1024, &c->threads) != 0) {
            fprintf(stderr, "surge: --threads needs an integer in [1, 1024], got '%s'\n", value ? value : "");
            return -1;
        }
        take_value(value, i);
    } else if (!strcmp(a, "--restart") || !strcmp(a, "--replay")) {
        const int restart = !strcmp(a, "--restart");
        if (!value) {
            fprintf(stderr, "surge: %s\n", restart ? "--restart needs a checkpoint file"
                                                   : "--replay needs a journal file (control.jsonl)");
            return -1;
        }
        *(restart ? &c->restart_path : &c->replay_path) = take_value(value, i);
    } else if (!strcmp(a, "--frames") || !strcmp(a, "--movie") || !strcmp(a, "--font")) {
        if (!value || value[0] == '\0') {
            fprintf(stderr, "surge: %s needs a %s\n", a, !strcmp(a, "--frames") ? "folder" : "file name");
            return -1;
        }
        *(!strcmp(a, "--frames") ? &c->frames_dir : !strcmp(a, "--movie") ? &c->movie_path : &c->font_path) =
            take_value(value, i);
    } else if (!strcmp(a, "--overwrite")) {
        c->overwrite = 1;
    } else {
        return 0;
    }
    return 1;
}

/* The live links: --publish, --control, --publish-every, --publish-hz, --publish-hwm, --curve-key,
 * --curve-clients, --paused */
static int parse_link_option(const char *a, const char *value, int *i, cli *c)
{
    if (!strcmp(a, "--publish") || !strcmp(a, "--control")) {
        const int publish = !strcmp(a, "--publish");
        if (!value || parse_endpoint(a, value, publish ? c->publish : c->control,
                                     publish ? &c->publish_remote : &c->control_remote) != 0) {
            if (!value)
                fprintf(stderr, "surge: %s needs an endpoint or a port\n", a);
            return -1;
        }
    } else if (!strcmp(a, "--publish-every")) {
        if (!value || parse_int(value, 1, 1000000000, &c->publisher.every_steps) != 0) {
            fprintf(stderr, "surge: --publish-every needs a whole number of steps in [1, 1e9], got '%s'\n",
                    value ? value : "");
            return -1;
        }
    } else if (!strcmp(a, "--publish-hz")) {
        if (!value || parse_real(value, 0, 1e6, &c->publisher.max_rate_hz) != 0) {
            fprintf(stderr, "surge: --publish-hz needs a rate in [0, 1e6] per second (0: no limit), got '%s'\n",
                    value ? value : "");
            return -1;
        }
    } else if (!strcmp(a, "--publish-hwm")) {
        if (!value || parse_int(value, 1, 1000000, &c->publisher.send_hwm) != 0) {
            fprintf(stderr, "surge: --publish-hwm needs a message count in [1, 1e6], got '%s'\n", value ? value : "");
            return -1;
        }
    } else if (!strcmp(a, "--curve-key") || !strcmp(a, "--curve-clients")) {
        if (!value || value[0] == '\0') {
            fprintf(stderr, "surge: %s needs a %s\n", a,
                    !strcmp(a, "--curve-key") ? "key file (NAME.key from surge keygen)"
                                               : "public key file or a folder of *.pub files");
            return -1;
        }
        *(!strcmp(a, "--curve-key") ? &c->curve_key_path : &c->curve_clients_path) = value;
    } else if (!strcmp(a, "--paused")) {
        c->paused = 1;
        return 1;
    } else {
        return 0;
    }
    take_value(value, i);
    return 1;
}

/* The rules across options, once all are read. */
static int check_option_combination(const cli *c, int allow_run_options)
{
    if (c->restart_path && c->case_path) {
        fprintf(stderr, "surge: give either a CASE or --restart CHECKPOINT, not both\n");
        return -1;
    }
    if (c->paused && !c->control[0]) {
        fprintf(stderr, "surge: --paused needs --control (nothing could resume the run)\n");
        return -1;
    }
    const size_t len = strlen(c->publish);
    const int wildcard_port = len > 2 && !strcmp(c->publish + len - 2, ":*"); /* two binds get two ports */
    if (c->publish[0] && c->control[0] && !strcmp(c->publish, c->control) && !wildcard_port) {
        fprintf(stderr, "surge: --publish and --control need different endpoints\n");
        return -1;
    }
    return allow_run_options ? check_endpoint_security(c) : 0;
}

int parse_cli(int argc, char **argv, cli *c, int allow_run_options)
{
    memset(c, 0, sizeof *c);
    c->publisher = surge_default_publisher_def();
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        const char *value = i + 1 < argc ? argv[i + 1] : NULL;
        int parsed = parse_override(a, value, &i, c);
        if (parsed == 0 && allow_run_options)
            parsed = parse_output_option(a, value, &i, c);
        if (parsed == 0 && allow_run_options)
            parsed = parse_link_option(a, value, &i, c);
        if (parsed < 0)
            return -1;
        if (parsed > 0)
            continue;
        if (a[0] == '-' && a[1] != '\0') {
            fprintf(stderr, "surge: unknown option '%s' (see --help)\n", a);
            return -1;
        } else if (!c->case_path) {
            c->case_path = a;
        } else {
            fprintf(stderr, "surge: unexpected argument '%s' (one case file at most)\n", a);
            return -1;
        }
    }
    return check_option_combination(c, allow_run_options);
}
