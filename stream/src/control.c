/* Control socket: JSON requests on a ROUTER socket, answered in the solver thread between steps (see
 * surge/control.h; commands and errors in docs/protocol.md). ROUTER rather than REP so that several clients
 * may be connected and a client that vanishes mid-request leaves nothing stuck: its reply is dropped. */
#define _POSIX_C_SOURCE 200809L
#include "surge/platform.h"
#include "surge/control.h"
#include "surge/endpoint.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zmq.h>

#include "peer_guard.h"
#include "surge/run.h"

enum { MAX_ENVELOPE_FRAMES = 8, PAUSED_POLL_MS = 100, MIN_C0_OVER_EXPECTED_SPEED = 10 };
/* a connection that has not completed ZeroMQ's greeting by then is closed; a peer that stops answering ZeroMQ's
 * heartbeats is closed; at most RECEIVE_QUEUE requests wait per peer, then ZeroMQ stops reading that peer */
enum { HANDSHAKE_MS = 2000, HEARTBEAT_MS = 5000, HEARTBEAT_TIMEOUT_MS = 15000, RECEIVE_QUEUE = 16 };
/* replies ZeroMQ queues for a client that does not read them (beyond the system's socket buffers); past that they are
 * owed (owed_replies) */
enum { REPLY_QUEUE = 1000 };
/* a request longer than this is refused before it is parsed: the longest real one, a text value of
 * SURGE_TEXT_PARAM_BYTES written as JSON escapes, is well below it */
enum { LONGEST_REQUEST = 8192 };
/* Control work is bounded by its cost in time: a running solver earns CONTROL_SHARE of the wall time between two
 * boundaries as credit (at most MAX_CREDIT_S saved up), and each request answered spends what it took, so a flood
 * costs the run at most that share of its time, however cheap or dear its requests, while a request to an idle
 * socket is answered at the next boundary. A paused run answers for up to PAUSED_BUDGET_S at a time. Requests left
 * waiting stay in ZeroMQ's queue, in order, and are answered at a later boundary. */
#define CONTROL_SHARE 0.02
#define MAX_CREDIT_S 0.01
#define MAX_DEBT_S 0.1 /* one dear request (a checkpoint of a large scene) leaves the socket deaf 5 s at most */
#define PAUSED_BUDGET_S 0.02
/* when the run ends, requests still waiting are refused until none has come for END_QUIET_MS (END_BUSY_QUIET_MS
 * once any came after the end: its client may still be sending, slowed by a busy machine) and none is owed; a client
 * owed refusals is served while it reads (one that reads nothing for END_STALL_S is left), for up to END_REFUSALS_S
 * in all, then the socket closes */
#define END_REFUSALS_S 5.0
#define END_STALL_S 1.0
enum { END_QUIET_MS = 100, END_BUSY_QUIET_MS = 500 };

/* Replies owed to a client whose queue to it is full (it has left REPLY_QUEUE replies unread): the first reply not
 * yet sent, and the number of "busy" refusals owed after it, one for each request that came from the client in the
 * meantime (those are not run). They go out in order as the client reads; a client that has gone is forgotten. */
typedef struct owed_replies {
    unsigned char identity[256];
    size_t identity_len;
    int delimited; /* a REQ client's: an empty frame before the reply */
    char *reply;   /* NULL once sent */
    long busy;
} owed_replies;

static const char BUSY_REPLY[] = "{\"ok\":false,\"error\":\"busy: this client has not read its earlier replies "
                                 "(the queue to it is full); the request was not run\"}";
static const char ENDED_REPLY[] = "{\"ok\":false,\"error\":\"the run has ended; the request was not run\"}";

struct surge_control {
    void *socket;
    char endpoint[SURGE_ENDPOINT_BYTES]; /* as bound: a wildcard port resolved */
    surge_journal *journal;
    int paused;
    int64_t pause_at_step; /* "step N" pauses again here; -1: no target */
    double start_wall_s;
    int64_t start_step;
    double credit_s;         /* the time requests may still take (CONTROL_SHARE of the time they were not served) */
    double service_end_s;    /* when the last boundary's work ended; < 0 before the first */
    peer_guard *guard;
    surge_params list_params; /* the parameters list_text was made from */
    char *list_text;          /* the "params" array of "list", kept until a parameter changes */
    owed_replies *owed;       /* one for each client whose queue was full */
    int owed_count, owed_capacity;
};

surge_control_def surge_default_control_def(void)
{
    surge_control_def d = {.endpoint = "tcp://127.0.0.1:5556", .start_paused = 0, .max_request_bytes = 16384,
                           .max_peers = 32, .idle_peer_s = 60};
    return d;
}

surge_control *surge_control_start(void *context, const surge_control_def *def, surge_journal *journal, char *err,
                                   size_t err_len)
{
    if (def->max_request_bytes < 64 || def->max_peers < 1) {
        snprintf(err, err_len, "control: max_request_bytes must be >= 64 and max_peers >= 1");
        return NULL;
    }
    surge_control *c = calloc(1, sizeof *c);
    if (!c) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    c->socket = zmq_socket(context, ZMQ_ROUTER);
    const int64_t max_bytes = def->max_request_bytes;
    const int linger_ms = 200, handshake_ms = HANDSHAKE_MS, heartbeat_ms = HEARTBEAT_MS,
              heartbeat_timeout_ms = HEARTBEAT_TIMEOUT_MS, receive_queue = RECEIVE_QUEUE, reply_queue = REPLY_QUEUE,
              mandatory = 1;
    /* ZMQ_ROUTER_MANDATORY: a reply that finds the client's queue full is not dropped but refused (EAGAIN), and kept */
    if (!c->socket || zmq_setsockopt(c->socket, ZMQ_MAXMSGSIZE, &max_bytes, sizeof max_bytes) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_ROUTER_MANDATORY, &mandatory, sizeof mandatory) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_LINGER, &linger_ms, sizeof linger_ms) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_HANDSHAKE_IVL, &handshake_ms, sizeof handshake_ms) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_HEARTBEAT_IVL, &heartbeat_ms, sizeof heartbeat_ms) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_HEARTBEAT_TIMEOUT, &heartbeat_timeout_ms, sizeof heartbeat_timeout_ms) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_RCVHWM, &receive_queue, sizeof receive_queue) != 0 ||
        zmq_setsockopt(c->socket, ZMQ_SNDHWM, &reply_queue, sizeof reply_queue) != 0 ||
        (def->curve && surge_curve_secure_socket(def->curve, c->socket, err, err_len) != 0) ||
        surge_endpoint_bind(c->socket, def->endpoint, "open the control socket on", c->endpoint, err, err_len) != 0) {
        if (c->socket)
            zmq_close(c->socket);
        free(c);
        return NULL;
    }
    if (!(c->guard = peer_guard_start(context, c->socket, def->max_peers, def->idle_peer_s, err, err_len))) {
        zmq_close(c->socket);
        free(c);
        return NULL;
    }
    c->journal = journal;
    c->service_end_s = -1;
    c->credit_s = MAX_CREDIT_S;
    c->paused = def->start_paused;
    c->pause_at_step = -1;
    c->start_wall_s = -1;
    return c;
}

const char *surge_control_endpoint(const surge_control *c) { return c->endpoint; }

static void refuse_waiting(surge_control *c, surge_control_end *end);
static long owed_replies_count(const surge_control *c);

void surge_control_close(surge_control *c, surge_control_end *end)
{
    surge_control_end ignored;
    if (!end)
        end = &ignored;
    *end = (surge_control_end){0};
    if (!c)
        return;
    refuse_waiting(c, end);
    end->undelivered = owed_replies_count(c);
    end->clients_left = c->owed_count;
    peer_guard_stop(c->guard);
    zmq_close(c->socket);
    for (int i = 0; i < c->owed_count; i++)
        free(c->owed[i].reply);
    free(c->owed);
    free(c->list_text);
    free(c);
}

void surge_control_peer_counts(const surge_control *c, long *over_limit, long *idle)
{
    peer_guard_counts(c ? c->guard : NULL, over_limit, idle);
}

/* ---- replies ---- */

/* Rewrites s in place as valid UTF-8 without control characters: each byte that does not start a complete,
 * well-formed sequence (a request's bytes, or a sequence cut by a length limit) becomes '?'. */
static void make_printable_utf8(char *s)
{
    unsigned char *in = (unsigned char *)s, *out = (unsigned char *)s;
    while (*in) {
        const unsigned char c = *in;
        int length = c < 0x80 ? 1 : (c & 0xE0) == 0xC0 ? 2 : (c & 0xF0) == 0xE0 ? 3 : (c & 0xF8) == 0xF0 ? 4 : 0;
        uint32_t code = length == 1 ? c : length == 2 ? c & 0x1F : length == 3 ? c & 0x0F : c & 0x07;
        for (int k = 1; k < length; k++) {
            if ((in[k] & 0xC0) != 0x80) {
                length = 0;
                break;
            }
            code = code << 6 | (in[k] & 0x3F);
        }
        static const uint32_t smallest[5] = {0, 0, 0x80, 0x800, 0x10000};
        if (length == 0 || code < smallest[length] || code > 0x10FFFF || (code >= 0xD800 && code < 0xE000) ||
            code < 0x20 || code == 0x7F) {
            *out++ = '?';
            in++;
            continue;
        }
        for (int k = 0; k < length; k++)
            *out++ = *in++;
    }
    *out = '\0';
}

static cJSON *error_reply(const char *format, const char *detail)
{
    char message[512];
    snprintf(message, sizeof message, format, detail);
    make_printable_utf8(message); /* never echo a request's bytes as invalid UTF-8 */
    cJSON *r = cJSON_CreateObject();
    cJSON_AddFalseToObject(r, "ok");
    cJSON_AddStringToObject(r, "error", message);
    return r;
}

static cJSON *ok_reply(const char *cmd, const surge_sim *sim)
{
    cJSON *r = cJSON_CreateObject();
    cJSON_AddTrueToObject(r, "ok");
    cJSON_AddStringToObject(r, "cmd", cmd);
    cJSON_AddNumberToObject(r, "step", (double)surge_sim_step_count(sim));
    cJSON_AddNumberToObject(r, "time_s", surge_sim_time(sim));
    return r;
}

/* A parameter's value as JSON: number, true/false, or the enum's name or the text. */
static cJSON *param_value(const surge_params *p, const surge_param_info *info)
{
    if (info->type == SURGE_PARAM_BOOL)
        return cJSON_CreateBool(surge_param_get_number(p, info) != 0);
    if (info->type == SURGE_PARAM_ENUM || info->type == SURGE_PARAM_TEXT) {
        char text[SURGE_TEXT_PARAM_BYTES];
        surge_param_format(p, info, text, sizeof text);
        return cJSON_CreateString(text);
    }
    return cJSON_CreateNumber(surge_param_get_number(p, info));
}

static void full_name(const surge_param_info *info, char *out, size_t len)
{
    snprintf(out, len, "%s.%s", info->section, info->key);
}

/* ---- commands ---- */

/* Every member of the request must be one the command reads: a typo such as "vlaue" is an error. */
static cJSON *check_members(const cJSON *request, const char *cmd, const char *const *allowed)
{
    for (const cJSON *m = request->child; m; m = m->next) {
        int known = !strcmp(m->string, "cmd");
        for (int i = 0; allowed[i]; i++)
            known |= !strcmp(m->string, allowed[i]);
        if (!known) {
            char detail[300];
            snprintf(detail, sizeof detail, "'%.120s' for command '%.40s'", m->string, cmd);
            return error_reply("unexpected member %s", detail);
        }
    }
    return NULL;
}

static const surge_param_info *find_key(const cJSON *request, cJSON **error)
{
    const cJSON *key = cJSON_GetObjectItemCaseSensitive(request, "key");
    if (!cJSON_IsString(key)) {
        *error = error_reply("%s", "\"key\" must be a string such as \"fluid.viscosity_m2ps\"");
        return NULL;
    }
    const surge_param_info *info = surge_param_find(key->valuestring);
    if (!info)
        *error = error_reply("unknown parameter '%.200s' (the \"list\" command names them all)", key->valuestring);
    return info;
}

/* The "params" array of "list" as JSON text. */
static char *list_params_text(const surge_sim *sim)
{
    cJSON *list = cJSON_CreateArray();
    static const char *const type_names[] = {"real", "int", "bool", "enum", "text"};
    for (int i = 0; i < surge_param_count(); i++) {
        const surge_param_info *info = surge_param_at(i);
        char name[128];
        full_name(info, name, sizeof name);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "key", name);
        cJSON_AddStringToObject(o, "type", type_names[info->type]);
        cJSON_AddStringToObject(o, "unit", info->unit);
        cJSON_AddItemToObject(o, "value", param_value(surge_sim_params(sim), info));
        cJSON_AddBoolToObject(o, "live", info->live);
        if (info->type == SURGE_PARAM_ENUM) {
            cJSON_AddStringToObject(o, "values", info->enum_names);
        } else if (info->type == SURGE_PARAM_REAL || info->type == SURGE_PARAM_INT) {
            cJSON_AddNumberToObject(o, "min", info->min_value);
            cJSON_AddNumberToObject(o, "max", info->max_value);
        }
        cJSON_AddStringToObject(o, "doc", info->doc);
        cJSON_AddItemToArray(list, o);
    }
    char *text = cJSON_PrintUnformatted(list);
    cJSON_Delete(list);
    return text;
}

/* The list is made again only after a parameter changed (by a request, a replayed journal or the run itself). */
static cJSON *command_list(surge_control *c, const surge_sim *sim)
{
    const surge_params *now = surge_sim_params(sim);
    if (!c->list_text || memcmp(&c->list_params, now, sizeof *now) != 0) {
        free(c->list_text);
        c->list_text = list_params_text(sim);
        memcpy(&c->list_params, now, sizeof *now);
    }
    if (!c->list_text)
        return error_reply("%s", "out of memory");
    cJSON *r = ok_reply("list", sim);
    cJSON_AddRawToObject(r, "params", c->list_text);
    return r;
}

static cJSON *command_get(const cJSON *request, const surge_sim *sim)
{
    cJSON *error = NULL;
    const surge_param_info *info = find_key(request, &error);
    if (!info)
        return error;
    char name[128];
    full_name(info, name, sizeof name);
    cJSON *r = ok_reply("get", sim);
    cJSON_AddStringToObject(r, "key", name);
    cJSON_AddItemToObject(r, "value", param_value(surge_sim_params(sim), info));
    cJSON_AddBoolToObject(r, "live", info->live);
    cJSON_AddStringToObject(r, "unit", info->unit);
    return r;
}

static cJSON *command_set(surge_control *c, const cJSON *request, surge_sim *sim)
{
    cJSON *error = NULL;
    const surge_param_info *info = find_key(request, &error);
    if (!info)
        return error;
    char name[128], text[128], previous[64], message[512];
    full_name(info, name, sizeof name);
    const cJSON *value = cJSON_GetObjectItemCaseSensitive(request, "value");
    if (cJSON_IsNumber(value) && (info->type == SURGE_PARAM_REAL || info->type == SURGE_PARAM_INT))
        snprintf(text, sizeof text, "%.17g", value->valuedouble);
    else if (cJSON_IsBool(value) && info->type == SURGE_PARAM_BOOL)
        snprintf(text, sizeof text, "%s", cJSON_IsTrue(value) ? "true" : "false");
    else if (!info->live)
        return error_reply("%s cannot change while the simulation runs", name);
    else if (cJSON_IsString(value) && info->type == SURGE_PARAM_ENUM) {
        const char *v = value->valuestring;
        if (!*v || isspace((unsigned char)v[0]) || isspace((unsigned char)v[strlen(v) - 1])) /* " cividis" */
            return error_reply("\"value\" for %s must be one of the names exactly, without spaces around it", name);
        snprintf(text, sizeof text, "%.100s", v);
    }
    else {
        static const char *const expected[] = {"a number", "a whole number", "true or false", "one of the names ",
                                               "text"};
        snprintf(message, sizeof message, "\"value\" for %s must be %s%s", name, expected[info->type],
                 info->type == SURGE_PARAM_ENUM ? info->enum_names : "");
        return error_reply("%s", message);
    }
    const surge_params before = *surge_sim_params(sim);
    surge_param_format(&before, info, previous, sizeof previous);
    const double speed_before_mps = surge_sim_expected_speed_mps(sim);
    if (surge_sim_set_param(sim, name, text, message, sizeof message) != 0)
        return error_reply("%s", message);
    char applied[64];
    surge_param_format(surge_sim_params(sim), info, applied, sizeof applied);
    if (c->journal)
        surge_journal_write(c->journal, sim, "control", "set", name, applied, previous);
    cJSON *r = ok_reply("set", sim);
    cJSON_AddStringToObject(r, "key", name);
    cJSON_AddItemToObject(r, "value", param_value(surge_sim_params(sim), info));
    cJSON_AddItemToObject(r, "previous", param_value(&before, info));
    cJSON_AddStringToObject(r, "applies", "from the next step on");
    /* c0 was derived at the start; a change that speeds the flow up can leave it too slow for weak compressibility */
    const double c0_mps = surge_sim_derived(sim)->c0_mps, speed_mps = surge_sim_expected_speed_mps(sim);
    if (speed_mps > speed_before_mps && c0_mps < MIN_C0_OVER_EXPECTED_SPEED * speed_mps) {
        snprintf(message, sizeof message, "c0 = %.3g m/s is now %.2g times the expected speed %.3g m/s (it should be "
                 "%d or more: density errors grow as (u/c0)^2 and the health monitor stops the run at "
                 "health.max_density_deviation); for this setting restart with a larger numerics.c0_factor or "
                 "numerics.c0_mps", c0_mps, c0_mps / speed_mps, speed_mps, MIN_C0_OVER_EXPECTED_SPEED);
        cJSON_AddStringToObject(r, "warning", message);
    }
    return r;
}

static cJSON *command_step(surge_control *c, const cJSON *request, surge_sim *sim)
{
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(request, "n");
    double count = 1;
    if (n) {
        if (!cJSON_IsNumber(n) || n->valuedouble < 1 || n->valuedouble > 1e9 || n->valuedouble != floor(n->valuedouble))
            return error_reply("%s", "\"n\" must be a whole number of steps in [1, 1e9]");
        count = n->valuedouble;
    }
    c->paused = 0;
    c->pause_at_step = surge_sim_step_count(sim) + (int64_t)count;
    char text[32];
    snprintf(text, sizeof text, "%.0f", count);
    if (c->journal)
        surge_journal_write(c->journal, sim, "control", "step", NULL, text, NULL);
    cJSON *r = ok_reply("step", sim);
    cJSON_AddNumberToObject(r, "n", count);
    cJSON_AddNumberToObject(r, "pauses_at_step", (double)c->pause_at_step);
    return r;
}

static cJSON *command_status(const surge_control *c, const surge_sim *sim)
{
    cJSON *r = ok_reply("status", sim);
    const double elapsed = surge_wall_clock_s() - c->start_wall_s;
    cJSON_AddNumberToObject(r, "dt_s", surge_sim_last_dt(sim));
    cJSON_AddNumberToObject(r, "end_s", surge_sim_params(sim)->time.end_s);
    cJSON_AddBoolToObject(r, "paused", c->paused);
    cJSON_AddNumberToObject(r, "mean_steps_per_s", elapsed > 0 ? (double)(surge_sim_step_count(sim) - c->start_step) / elapsed : 0);
    cJSON_AddStringToObject(r, "health", surge_health_check_name(surge_sim_health(sim)->check));
    cJSON_AddNumberToObject(r, "fluid_count", surge_sim_derived(sim)->fluid_count);
    return r;
}

/* A simple command with no members but "cmd", journaled: pause, resume, snapshot, checkpoint, stop. */
static cJSON *command_simple(surge_control *c, const char *cmd, surge_sim *sim, int *requests)
{
    cJSON *r = ok_reply(cmd, sim);
    if (!strcmp(cmd, "pause")) {
        c->paused = 1;
        c->pause_at_step = -1;
    } else if (!strcmp(cmd, "resume")) {
        c->paused = 0;
        c->pause_at_step = -1;
    } else if (!strcmp(cmd, "snapshot")) {
        char file[64];
        surge_run_snapshot_name(surge_sim_step_count(sim), file, sizeof file);
        cJSON_AddStringToObject(r, "file", file);
        *requests |= SURGE_REQUEST_SNAPSHOT;
    } else if (!strcmp(cmd, "checkpoint")) {
        cJSON_AddStringToObject(r, "file", "checkpoint.bin");
        *requests |= SURGE_REQUEST_CHECKPOINT;
    } else {
        *requests |= SURGE_REQUEST_STOP;
    }
    if (c->journal)
        surge_journal_write(c->journal, sim, "control", cmd, NULL, NULL, NULL);
    cJSON_AddBoolToObject(r, "paused", c->paused);
    return r;
}

#define COMMAND_NAMES "list, get, set, pause, resume, step, snapshot, checkpoint, status, stop"

typedef struct command {
    const char *name;
    const char *const *members; /* besides "cmd", NULL-terminated */
} command;

static const char *const no_members[] = {NULL}, *const key_only[] = {"key", NULL},
                         *const key_value[] = {"key", "value", NULL}, *const step_members[] = {"n", NULL};
static const command commands[] = {
    {"list", no_members},      {"get", key_only},        {"set", key_value},          {"pause", no_members},
    {"resume", no_members},    {"step", step_members},   {"snapshot", no_members},    {"checkpoint", no_members},
    {"status", no_members},    {"stop", no_members},
};

static const command *find_command(const char *name)
{
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(commands[i].name, name))
            return &commands[i];
    return NULL;
}

static cJSON *run_command(surge_control *c, const char *name, const cJSON *request, surge_sim *sim, int *requests)
{
    if (!strcmp(name, "list"))
        return command_list(c, sim);
    if (!strcmp(name, "get"))
        return command_get(request, sim);
    if (!strcmp(name, "set"))
        return command_set(c, request, sim);
    if (!strcmp(name, "step"))
        return command_step(c, request, sim);
    if (!strcmp(name, "status"))
        return command_status(c, sim);
    return command_simple(c, name, sim, requests);
}

/* The first number token outside strings that JSON's grammar rejects (-?(0|[1-9][0-9]*)(.[0-9]+)?([eE][+-]?[0-9]+)?),
 * or NULL. */
static const char *non_json_number(const char *text)
{
    int in_string = 0;
    for (const char *p = text; *p; p++) {
        if (in_string) {
            if (*p == '\\' && p[1])
                p++;
            else if (*p == '"')
                in_string = 0;
            continue;
        }
        if (*p == '"') {
            in_string = 1;
            continue;
        }
        if (!(isdigit((unsigned char)*p) || *p == '-' || *p == '+' || *p == '.'))
            continue;
        const char *start = p, *q = p;
        if (*q == '-')
            q++;
        if (*q == '0')
            q++;
        else if (isdigit((unsigned char)*q))
            while (isdigit((unsigned char)*q))
                q++;
        else
            return start;
        if (*q == '.') {
            if (!isdigit((unsigned char)*++q))
                return start;
            while (isdigit((unsigned char)*q))
                q++;
        }
        if (*q == 'e' || *q == 'E') {
            q++;
            if (*q == '+' || *q == '-')
                q++;
            if (!isdigit((unsigned char)*q))
                return start;
            while (isdigit((unsigned char)*q))
                q++;
        }
        if (isdigit((unsigned char)*q) || *q == '.' || *q == '+' || *q == '-' || *q == 'e' || *q == 'E')
            return start; /* 01, 1.2.3, 1e5e5 */
        p = q - 1;
    }
    return NULL;
}

static cJSON *handle_request(surge_control *c, const char *body, size_t len, surge_sim *sim, int *requests)
{
    if (memchr(body, '\0', len))
        return error_reply("%s", "request contains a NUL byte; send one JSON object as UTF-8 text");
    if (strstr(body, "\\u0000")) /* cJSON would cut the string there: "status\u0000junk" would run as status */
        return error_reply("%s", "request contains \\u0000 (a NUL character) in a string");
    const char *bad_number = non_json_number(body);
    if (bad_number) /* cJSON reads 01 as 1 and +1 as 1; JSON has neither */
        return error_reply("request holds a number JSON does not allow near '%.20s'", bad_number);
    const char *end = NULL;
    cJSON *request = cJSON_ParseWithOpts(body, &end, 1);
    if (!request) {
        char detail[64];
        snprintf(detail, sizeof detail, "%ld", end ? (long)(end - body) : 0L);
        return error_reply("request is not valid JSON (error near byte %s)", detail);
    }
    cJSON *reply = NULL;
    const cJSON *cmd = cJSON_GetObjectItemCaseSensitive(request, "cmd");
    if (!cJSON_IsObject(request))
        reply = error_reply("%s", "request must be a JSON object such as {\"cmd\": \"status\"}");
    else if (!cJSON_IsString(cmd))
        reply = error_reply("%s", "request needs \"cmd\": a string (" COMMAND_NAMES ")");
    else {
        const command *found = find_command(cmd->valuestring);
        if (!found)
            reply = error_reply("unknown command '%.100s' (" COMMAND_NAMES ")", cmd->valuestring);
        else if (!(reply = check_members(request, found->name, found->members)))
            reply = run_command(c, found->name, request, sim, requests);
    }
    cJSON_Delete(request);
    return reply;
}

/* ---- the socket ---- */

/* Sends a reply through a client's envelope: 0 when it is queued or the client has gone (nothing more to do for it),
 * -1 when the client's queue is full (EAGAIN: try again later). */
static int send_reply(surge_control *c, const void *identity, size_t identity_len, int delimited, const char *text)
{
    if (zmq_send(c->socket, identity, identity_len, ZMQ_SNDMORE | ZMQ_DONTWAIT) < 0)
        return zmq_errno() == EAGAIN ? -1 : 0; /* EHOSTUNREACH: the client has gone */
    /* the rest of a message whose first frame was taken is taken too */
    if (delimited)
        zmq_send(c->socket, "", 0, ZMQ_SNDMORE | ZMQ_DONTWAIT);
    zmq_send(c->socket, text, strlen(text), ZMQ_DONTWAIT);
    return 0;
}

static owed_replies *owed_to(surge_control *c, const void *identity, size_t identity_len)
{
    for (int i = 0; i < c->owed_count; i++)
        if (c->owed[i].identity_len == identity_len && !memcmp(c->owed[i].identity, identity, identity_len))
            return &c->owed[i];
    return NULL;
}

/* Keeps a reply the client's full queue refused (text is taken over); 0, or -1 out of memory (text freed) */
static int owe_reply(surge_control *c, const void *identity, size_t identity_len, int delimited, char *text)
{
    if (identity_len > sizeof c->owed[0].identity) {
        free(text);
        return -1;
    }
    if (c->owed_count == c->owed_capacity) {
        const int capacity = c->owed_capacity ? 2 * c->owed_capacity : 4;
        owed_replies *grown = realloc(c->owed, (size_t)capacity * sizeof *grown);
        if (!grown) {
            free(text);
            return -1;
        }
        c->owed = grown;
        c->owed_capacity = capacity;
    }
    owed_replies *o = &c->owed[c->owed_count++];
    memcpy(o->identity, identity, identity_len);
    o->identity_len = identity_len;
    o->delimited = delimited;
    o->reply = text;
    o->busy = 0;
    return 0;
}

/* Sends what is owed, in order, as far as the clients' queues take it */
static void send_owed(surge_control *c)
{
    for (int i = 0; i < c->owed_count;) {
        owed_replies *o = &c->owed[i];
        int full = 0;
        while (!full && (o->reply || o->busy > 0)) {
            full = send_reply(c, o->identity, o->identity_len, o->delimited, o->reply ? o->reply : BUSY_REPLY) != 0;
            if (!full && o->reply) {
                free(o->reply);
                o->reply = NULL;
            } else if (!full) {
                o->busy--;
            }
        }
        if (full) {
            i++;
            continue;
        }
        c->owed[i] = c->owed[--c->owed_count]; /* all sent, or the client has gone */
    }
}

/* Receives one request: [identity][empty delimiter, from REQ clients][body]. Answers it in the same envelope, or,
 * when ended, refuses it (the run is over). A client still owed replies is answered "busy" without running the
 * request. Returns 0 when nothing was waiting. */
static int receive_one(surge_control *c, surge_sim *sim, int *requests, int ended)
{
    zmq_msg_t frames[MAX_ENVELOPE_FRAMES];
    int count = 0, more = 1, overflow = 0;
    while (more) {
        zmq_msg_t part;
        zmq_msg_init(&part);
        if (zmq_msg_recv(&part, c->socket, count == 0 ? ZMQ_DONTWAIT : 0) < 0) {
            zmq_msg_close(&part);
            break;
        }
        more = zmq_msg_more(&part);
        if (count < MAX_ENVELOPE_FRAMES) {
            zmq_msg_init(&frames[count]);
            zmq_msg_move(&frames[count++], &part);
        } else {
            overflow = 1;
        }
        zmq_msg_close(&part);
    }
    if (count == 0)
        return 0;
    int source_fd = -1;
    if (zmq_msg_get(&frames[count - 1], ZMQ_SRCFD) >= 0) /* the peer's connection, for its idle time */
        source_fd = zmq_msg_get(&frames[count - 1], ZMQ_SRCFD);
    peer_guard_touch(c->guard, source_fd);
    const int delimited = count >= 3 && zmq_msg_size(&frames[1]) == 0;
    const int head = delimited ? 2 : 1; /* identity (+ delimiter) */
    owed_replies *owed = owed_to(c, zmq_msg_data(&frames[0]), zmq_msg_size(&frames[0]));
    cJSON *reply = NULL;
    if (owed || ended) {
        if (owed)
            owed->busy++;
        else if (send_reply(c, zmq_msg_data(&frames[0]), zmq_msg_size(&frames[0]), delimited, ENDED_REPLY) != 0)
            owe_reply(c, zmq_msg_data(&frames[0]), zmq_msg_size(&frames[0]), delimited, strdup(ENDED_REPLY));
        for (int i = 0; i < count; i++)
            zmq_msg_close(&frames[i]);
        return 1;
    }
    if (count < 2)
        reply = error_reply("%s", "empty request");
    else if (overflow || count != head + 1)
        reply = error_reply("%s", "a request is one frame holding one JSON object");
    else if (zmq_msg_size(&frames[head]) > LONGEST_REQUEST) {
        char detail[64];
        snprintf(detail, sizeof detail, "%zu bytes; at most %d", zmq_msg_size(&frames[head]), (int)LONGEST_REQUEST);
        reply = error_reply("request too long (%s), not read", detail);
    } else {
        const size_t len = zmq_msg_size(&frames[head]);
        char *body = malloc(len + 1);
        if (!body)
            reply = error_reply("%s", "out of memory");
        else {
            memcpy(body, zmq_msg_data(&frames[head]), len);
            body[len] = '\0';
            reply = handle_request(c, body, len, sim, requests);
            free(body);
        }
    }
    char *text = cJSON_PrintUnformatted(reply);
    cJSON_Delete(reply);
    /* the reply goes back through the same envelope; a client that has gone is skipped, one whose queue is full is
     * owed it */
    const char *sent = text ? text : "{\"ok\":false,\"error\":\"out of memory\"}";
    if (send_reply(c, zmq_msg_data(&frames[0]), zmq_msg_size(&frames[0]), delimited, sent) != 0) {
        owe_reply(c, zmq_msg_data(&frames[0]), zmq_msg_size(&frames[0]), delimited, text ? text : strdup(sent));
        text = NULL;
    }
    free(text);
    for (int i = 0; i < count; i++)
        zmq_msg_close(&frames[i]);
    return 1;
}

static int serve_one(surge_control *c, surge_sim *sim, int *requests)
{
    return receive_one(c, sim, requests, 0);
}

/* The replies owed to clients whose queues are full */
static long owed_replies_count(const surge_control *c)
{
    long count = 0;
    for (int i = 0; i < c->owed_count; i++)
        count += (c->owed[i].reply != NULL) + c->owed[i].busy;
    return count;
}

/* Sends what is owed as far as the clients read; returns whether anything went out */
static int send_owed_progress(surge_control *c)
{
    const long before = owed_replies_count(c);
    send_owed(c);
    return owed_replies_count(c) < before;
}

/* The run has ended: each request still waiting, or arriving until none has for END_QUIET_MS (END_BUSY_QUIET_MS
 * once any has), is refused, and what is owed is sent as the clients read, until they stop reading for
 * END_STALL_S; for END_REFUSALS_S at most, then the socket closes */
static void refuse_waiting(surge_control *c, surge_control_end *end)
{
    const double start_s = surge_wall_clock_s();
    double progress_s = start_s;
    int requests = 0;
    while (surge_wall_clock_s() - start_s < END_REFUSALS_S) {
        if (send_owed_progress(c))
            progress_s = surge_wall_clock_s();
        while (receive_one(c, NULL, &requests, 1) && surge_wall_clock_s() - start_s < END_REFUSALS_S) {
            progress_s = surge_wall_clock_s();
            end->refused++;
        }
        if (send_owed_progress(c))
            progress_s = surge_wall_clock_s();
        if (c->owed_count > 0 && surge_wall_clock_s() - progress_s > END_STALL_S) {
            end->stalled = 1;
            return;
        }
        zmq_pollitem_t item = {.socket = c->socket, .events = ZMQ_POLLIN};
        const int quiet_ms = end->refused > 0 ? END_BUSY_QUIET_MS : END_QUIET_MS;
        if (zmq_poll(&item, 1, c->owed_count > 0 ? 10 : quiet_ms) <= 0 && c->owed_count == 0)
            return;
    }
    end->time_limit = 1;
}

/* Answers requests until the budget from start_s is spent (at least one, if any is waiting). */
static void serve_for(surge_control *c, surge_sim *sim, int *requests, double start_s, double budget_s)
{
    while (serve_one(c, sim, requests) && surge_wall_clock_s() - start_s < budget_s)
        ;
}

int surge_control_service(surge_control *c, surge_sim *sim, volatile sig_atomic_t *stop_signal)
{
    const double start_s = surge_wall_clock_s();
    send_owed(c);
    if (c->start_wall_s < 0) {
        c->start_wall_s = start_s;
        c->start_step = surge_sim_step_count(sim);
    }
    if (c->service_end_s >= 0 && !c->paused)
        c->credit_s = fmin(c->credit_s + CONTROL_SHARE * (start_s - c->service_end_s), MAX_CREDIT_S);
    if (c->pause_at_step >= 0 && surge_sim_step_count(sim) >= c->pause_at_step) {
        c->paused = 1;
        c->pause_at_step = -1;
    }
    /* a flood of requests costs the run at most CONTROL_SHARE of its time and never stops it */
    int requests = SURGE_CONTINUE;
    if (c->paused)
        serve_for(c, sim, &requests, start_s, PAUSED_BUDGET_S);
    else
        while (c->credit_s > 0) {
            const double request_start_s = surge_wall_clock_s();
            if (!serve_one(c, sim, &requests))
                break;
            c->credit_s = fmax(c->credit_s - (surge_wall_clock_s() - request_start_s), -MAX_DEBT_S);
        }
    if (!c->paused || (requests & SURGE_REQUEST_STOP) || (stop_signal && *stop_signal)) {
        c->service_end_s = surge_wall_clock_s();
        return requests;
    }
    /* paused: wait a little for the next request, then let the run loop come back (it publishes, checks
     * signals) before any step */
    if (!requests) {
        zmq_pollitem_t item = {.socket = c->socket, .events = ZMQ_POLLIN};
        if (zmq_poll(&item, 1, PAUSED_POLL_MS) > 0)
            serve_for(c, sim, &requests, surge_wall_clock_s(), PAUSED_BUDGET_S);
    }
    c->service_end_s = surge_wall_clock_s();
    return requests | (c->paused && !(requests & SURGE_REQUEST_STOP) ? SURGE_REQUEST_AGAIN : 0);
}
