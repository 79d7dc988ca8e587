/* State publisher: an XPUB socket fed by a mailbox, in its own thread (see surge/publisher.h and
 * docs/protocol.md for the wire format). XPUB rather than PUB so that the publisher sees subscriptions:
 * nothing is copied out of the solver while nobody listens, and a subscriber may ask for a subset of the
 * particle fields by subscribing to "state/name,name,...". */
#define _POSIX_C_SOURCE 200809L
#include "surge/endpoint.h"
#include "surge/platform.h"
#include "surge/publisher.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <zmq.h>

#include "peer_guard.h"
#include "surge/mailbox.h"

#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__
#error "the wire format sends arrays in memory order, which must be little-endian"
#endif

enum { SCHEMA_VERSION = 1, MAX_SUBSCRIPTION_BYTES = 256, JUNK_SHOWN = 5 };
enum { WANT_STATE = 1, WANT_BODIES = 2, WANT_STATS = 4 };

/* The final frame is not dropped at a full queue: the publisher waits up to this long for room, so a
   subscriber that keeps reading gets the run's last state and its "final" stats; a stalled one delays the
   end of the run by at most this. */
static const double FINAL_DELIVERY_WAIT_S = 2.0;

/* The newest rendered frame, handed over by the renderer thread. */
typedef struct png_slot {
    pthread_mutex_t lock;
    uint8_t *png;
    size_t len;
    int64_t step;
    double time_s;
    uint64_t sequence;
    int fresh;
} png_slot;

/* The particle fields of the "state" topic, in the order they are sent. */
typedef struct state_field {
    const char *name, *dtype, *unit;
    size_t element_bytes;
} state_field;

static const state_field state_fields[] = {
    {"x_m", "f64", "m", 8},
    {"y_m", "f64", "m", 8},
    {"vx_mps", "f32", "m/s", 4},
    {"vy_mps", "f32", "m/s", 4},
    {"density_kgpm3", "f32", "kg/m^3", 4},
    {"pressure_pa", "f32", "Pa", 4},
    {"kind", "u8", "0 fluid, 1 wall, 2 moving wall, 3 boulder", 1},
    {"id", "i32", "-", 4},
};
enum { STATE_FIELD_COUNT = sizeof state_fields / sizeof state_fields[0] };

/* Subscriptions. Every subscription that can receive something is kept, and the table cannot be filled:
 * - the plain topics' prefixes ("", "s", ..., "state", "state/", "stats", "b", ..., "frame"): PLAIN_PREFIXES in all;
 * - field subsets "state/a,b,c": an ordered choice of distinct fields, SUBSET_CODES of them in all (8 fields), one
 *   slot each. A peer subscribing to many of them takes no slot another needs; at most SUBSETS_PER_STATE are sent
 *   per state, taking turns, so every subscribed subset gets a state at least every SUBSET_CODES / SUBSETS_PER_STATE
 *   states.
 * Anything else (an unknown or repeated field, a topic surge never sends, a NUL byte) can match nothing and is not
 * kept.
 * A slot counts the connections that hold it and is released when the last one unsubscribes or leaves. The socket is
 * ZMQ_XPUB_VERBOSER, so every (un)subscribe message reaches the publisher, but ZeroMQ also passes on an unsubscribe
 * for a topic the peer never subscribed to (it cannot tell it from a last subscriber leaving): such a message must
 * not release a slot other peers hold. So each connection's own subscriptions are kept (struct subscriber), as
 * ZeroMQ keeps them for it (a topic at most once per connection); a message is known by its connection's descriptor
 * (ZMQ_SRCFD) and the number the ZAP handler gave that connection (its "User-Id", surge/curve.h), which tells a
 * descriptor's next connection from the one before (ZeroMQ sets both properties itself: a peer cannot replace them with
 * its own in its handshake). ZeroMQ's own unsubscribes for a connection that left carry no
 * descriptor: they release one hold each. */
enum { PLAIN_PREFIXES = 19, SUBSET_CODES = 109600, SUBSETS_PER_STATE = 16 };
_Static_assert(STATE_FIELD_COUNT == 8, "SUBSET_CODES is 8 + 8*7 + ... + 8!, the ordered choices of 8 fields");
enum { SUBSET_WORDS = (SUBSET_CODES + 63) / 64 };
static const char *const plain_topics[PLAIN_PREFIXES] = {
    "", "s", "st", "sta", "stat", "state", "state/", "stats", "b", "bo", "bod", "bodi", "bodie", "bodies",
    "f", "fr", "fra", "fram", "frame"};

/* One subscriber connection's subscriptions (a slot at most once each, as ZeroMQ holds them for it) */
typedef struct subscriber {
    int fd;            /* its connection's descriptor */
    uint64_t number;   /* the ZAP handler's number for the connection; 0 without one */
    uint32_t plain;    /* bit i: plain_topics[i] */
    uint64_t *subsets; /* bit c: the subset of code c; NULL until it holds one */
} subscriber;

static const void *state_field_data(const surge_snapshot *s, int field)
{
    switch (field) {
    case 0: return s->x_m;
    case 1: return s->y_m;
    case 2: return s->vx_mps;
    case 3: return s->vy_mps;
    case 4: return s->density_kgpm3;
    case 5: return s->pressure_pa;
    case 6: return s->kind;
    default: return s->id;
    }
}

/* The rigid bodies (boulders) of the "bodies" topic; count 0 in a scene without boulders. */
static const state_field body_fields[] = {
    {"x_m", "f64", "m", 8},           {"y_m", "f64", "m", 8},         {"angle_rad", "f64", "rad", 8},
    {"vx_mps", "f64", "m/s", 8},      {"vy_mps", "f64", "m/s", 8},    {"omega_radps", "f64", "rad/s", 8},
    {"radius_m", "f64", "m", 8},
};
enum { BODY_FIELD_COUNT = sizeof body_fields / sizeof body_fields[0] };

struct surge_publisher {
    surge_publisher_def def;
    void *socket;
    char endpoint[SURGE_ENDPOINT_BYTES]; /* as bound: a wildcard port resolved */
    surge_mailbox *mailbox;
    pthread_t thread;
    peer_guard *guard;
    atomic_int wanted;    /* WANT_* of the current subscriptions, written by the publisher thread */
    atomic_int finishing; /* set by the solver thread before the final frame */
    /* solver thread */
    double start_wall_s, last_wall_s;
    int64_t last_step;
    surge_params last_params; /* as posted last: a change of a live parameter is posted at once */
    /* publisher thread */
    uint32_t plain_holders[PLAIN_PREFIXES]; /* connections holding plain_topics[i] */
    uint32_t *subset_holders;               /* [SUBSET_CODES]: connections holding the subset of code c */
    uint64_t subsets[SUBSET_WORDS];         /* bit c: the subset of code c is subscribed (has a holder) */
    int subset_count, subset_turn;          /* subset_turn: the code the next state's subsets start from */
    subscriber *subscribers;                /* by descriptor, one for each connection seen (the newest on it) */
    int subscriber_count, subscriber_capacity;
    int junk_count, turns_told;
    uint64_t messages_sent, bytes_sent;
    double deliver_until_s; /* > 0 while sending the final frame: wait for queue room until this wall time */
    png_slot frame;
};

surge_publisher_def surge_default_publisher_def(void)
{
    surge_publisher_def d = {.endpoint = "tcp://127.0.0.1:5555", .every_steps = 1, .max_rate_hz = 30.0,
                             .send_hwm = 4, .max_peers = 64};
    return d;
}

/* A message whose topic starts with a subscription reaches that subscriber (ZeroMQ prefix matching); the subsets'
 * own topics are sent only to their subscribers. */
static int subscribed_to(const surge_publisher *p, const char *topic)
{
    for (int i = 0; i < PLAIN_PREFIXES; i++)
        if (p->plain_holders[i] > 0 && !strncmp(topic, plain_topics[i], strlen(plain_topics[i])))
            return 1;
    return 0;
}

static void update_wanted(surge_publisher *p)
{
    int wanted = p->subset_count > 0 ? WANT_STATE : 0;
    wanted |= subscribed_to(p, "state") ? WANT_STATE : 0;
    wanted |= subscribed_to(p, "bodies") ? WANT_BODIES : 0;
    wanted |= subscribed_to(p, "stats") ? WANT_STATS : 0;
    atomic_store(&p->wanted, wanted);
}

/* The index in plain_topics of a prefix of a plain topic we send or of every field subset's ("state/"); -1 if none */
static int plain_prefix(const char *topic)
{
    for (int i = 0; i < PLAIN_PREFIXES; i++)
        if (!strcmp(plain_topics[i], topic))
            return i;
    return -1;
}

/* The ordered choices of k of n fields */
static int permutations(int n, int k)
{
    int count = 1;
    for (int i = 0; i < k; i++)
        count *= n - i;
    return count;
}

/* A subset's code in [0, SUBSET_CODES): the shorter subsets first, then each field's rank among those not yet
 * chosen (a mixed-radix number). */
static int subset_code(const int *indices, int count)
{
    int code = 0, used = 0;
    for (int k = 1; k < count; k++)
        code += permutations(STATE_FIELD_COUNT, k);
    for (int i = 0; i < count; i++) {
        int smaller = 0;
        for (int v = 0; v < indices[i]; v++)
            smaller += !(used >> v & 1);
        code += smaller * permutations(STATE_FIELD_COUNT - i - 1, count - i - 1);
        used |= 1 << indices[i];
    }
    return code;
}

/* The fields of a subset's code, inverse of subset_code; their count */
static int subset_indices(int code, int *indices)
{
    int count = 1;
    for (; code >= permutations(STATE_FIELD_COUNT, count); count++)
        code -= permutations(STATE_FIELD_COUNT, count);
    int used = 0;
    for (int i = 0; i < count; i++) {
        const int weight = permutations(STATE_FIELD_COUNT - i - 1, count - i - 1);
        int smaller = code / weight, v = 0;
        code %= weight;
        while ((used >> v & 1) || smaller-- > 0)
            v++;
        indices[i] = v;
        used |= 1 << v;
    }
    return count;
}

/* Parses "state/a,b,c" into field indices; 0 when a name is unknown, repeated or empty. */
static int parse_field_subset(const char *subscription, int *indices, int *count)
{
    const char *s = subscription + strlen("state/");
    *count = 0;
    while (*s) {
        const size_t len = strcspn(s, ",");
        int found = -1;
        for (int i = 0; i < STATE_FIELD_COUNT; i++)
            if (strlen(state_fields[i].name) == len && !strncmp(s, state_fields[i].name, len))
                found = i;
        for (int k = 0; k < *count; k++)
            if (indices[k] == found)
                found = -1;
        if (found < 0 || (s[len] == ',' && s[len + 1] == '\0'))
            return 0;
        indices[(*count)++] = found;
        s += len + (s[len] == ',');
    }
    return *count > 0;
}

static void ignore_subscription(surge_publisher *p, const char *topic, size_t len, const char *why)
{
    if (p->junk_count++ < JUNK_SHOWN)
        fprintf(stderr, "surge: publisher: not keeping the subscription '%.*s' (%zu bytes): %s%s\n",
                (int)(len < 80 ? len : 80), topic, len, why,
                p->junk_count == JUNK_SHOWN ? " (further ones are not shown)" : "");
}

/* The record of the connection on descriptor fd whose ZAP number is number: a new one, or the one before on that
 * descriptor emptied when number is newer (that connection has gone: ZeroMQ passes a connection's messages on before
 * those of a later connection on its descriptor). NULL when number is older than the record's (a message of a
 * connection that has gone, which should not come so late) or out of memory. */
static subscriber *subscriber_of(surge_publisher *p, int fd, uint64_t number)
{
    for (int i = 0; i < p->subscriber_count; i++) {
        subscriber *s = &p->subscribers[i];
        if (s->fd != fd)
            continue;
        if (number < s->number)
            return NULL;
        if (number > s->number) {
            s->number = number;
            s->plain = 0;
            if (s->subsets)
                memset(s->subsets, 0, SUBSET_WORDS * sizeof *s->subsets);
        }
        return s;
    }
    if (p->subscriber_count == p->subscriber_capacity) {
        const int capacity = p->subscriber_capacity ? 2 * p->subscriber_capacity : 16;
        subscriber *grown = realloc(p->subscribers, (size_t)capacity * sizeof *grown);
        if (!grown)
            return NULL;
        p->subscribers = grown;
        p->subscriber_capacity = capacity;
    }
    subscriber *s = &p->subscribers[p->subscriber_count++];
    *s = (subscriber){.fd = fd, .number = number};
    return s;
}

/* A slot (a plain topic's index, or SUBSET_SLOT + a subset's code) held by one connection more or less */
enum { SUBSET_SLOT = PLAIN_PREFIXES };
static void count_holder(surge_publisher *p, int slot, int delta)
{
    uint32_t *holders = slot < SUBSET_SLOT ? &p->plain_holders[slot] : &p->subset_holders[slot - SUBSET_SLOT];
    if (delta < 0 && *holders == 0)
        return;
    *holders += (uint32_t)delta;
    if (slot < SUBSET_SLOT || *holders != (delta > 0 ? 1u : 0u))
        return;
    const int code = slot - SUBSET_SLOT;
    p->subsets[code / 64] ^= UINT64_C(1) << (code % 64);
    p->subset_count += delta;
    if (p->subset_count > SUBSETS_PER_STATE && !p->turns_told++)
        fprintf(stderr, "surge: publisher: more than %d distinct field subsets subscribed: they take turns, "
                "%d per state\n", SUBSETS_PER_STATE, SUBSETS_PER_STATE);
}

/* Sets or clears (hold 1 or 0) connection s's hold of slot: 1 when that changed it, 0 when it did not, -1 when there
 * was no memory to record it */
static int set_held(subscriber *s, int slot, int hold)
{
    uint64_t *word = NULL, bit = 0;
    if (slot < SUBSET_SLOT) {
        if (!!(s->plain >> slot & 1) == hold)
            return 0;
        s->plain ^= UINT32_C(1) << slot;
        return 1;
    }
    const int code = slot - SUBSET_SLOT;
    if (!s->subsets && !hold)
        return 0;
    if (!s->subsets && !(s->subsets = calloc(SUBSET_WORDS, sizeof *s->subsets)))
        return -1;
    word = &s->subsets[code / 64];
    bit = UINT64_C(1) << (code % 64);
    if (!!(*word & bit) == hold)
        return 0;
    *word ^= bit;
    return 1;
}

/* One (un)subscription message (msg: first byte 1 or 0, then the topic) */
static void note_subscription(surge_publisher *p, zmq_msg_t *msg)
{
    const int subscribe = ((const char *)zmq_msg_data(msg))[0] == 1;
    const size_t len = zmq_msg_size(msg) - 1;
    char topic[MAX_SUBSCRIPTION_BYTES + 1];
    memcpy(topic, (const char *)zmq_msg_data(msg) + 1, len < sizeof topic ? len : sizeof topic - 1);
    topic[len < sizeof topic ? len : sizeof topic - 1] = '\0';
    int indices[STATE_FIELD_COUNT], count = 0, slot = -1;
    if (len > MAX_SUBSCRIPTION_BYTES || strlen(topic) != len) {
        if (subscribe)
            ignore_subscription(p, topic, len, len > MAX_SUBSCRIPTION_BYTES ? "too long" : "it holds a NUL byte");
    } else if (!strncmp(topic, "state/", 6) && topic[6]) {
        if (parse_field_subset(topic, indices, &count))
            slot = SUBSET_SLOT + subset_code(indices, count);
        else if (subscribe)
            ignore_subscription(p, topic, len, "it names a field that does not exist, or one twice");
    } else if ((slot = plain_prefix(topic)) < 0 && subscribe) {
        ignore_subscription(p, topic, len, "surge sends no topic it could match");
    }
    if (slot < 0)
        return;
    /* from a connection (its descriptor), or ZeroMQ's own unsubscribe for one that left (none) */
    const int fd = zmq_msg_get(msg, ZMQ_SRCFD);
    if (fd < 0) {
        count_holder(p, slot, subscribe ? 1 : -1);
        return;
    }
    const char *number_text = zmq_msg_gets(msg, "User-Id");
    const uint64_t number = number_text ? strtoull(number_text, NULL, 10) : 0;
    subscriber *s = subscriber_of(p, fd, number);
    /* a second subscribe from a connection is one hold, as ZeroMQ keeps it; a hold that could not be recorded (or a
     * message from a connection that has gone, or any without the ZAP number, whose descriptor's earlier connection
     * may have held it) is counted all the same and only released when the connection leaves: a slot may be kept too
     * long, never taken from a subscriber */
    if (subscribe && (!s || set_held(s, slot, 1) != 0 || number == 0))
        count_holder(p, slot, 1);
    else if (!subscribe && s && set_held(s, slot, 0) == 1)
        count_holder(p, slot, -1); /* an unsubscribe for what it did not hold releases nothing */
}

/* Reads the (un)subscription messages XPUB delivers: first byte 1 or 0, then the topic. */
static void read_subscriptions(surge_publisher *p)
{
    zmq_msg_t msg;
    zmq_msg_init(&msg);
    while (zmq_msg_recv(&msg, p->socket, ZMQ_DONTWAIT) >= 0) {
        const unsigned char *data = zmq_msg_data(&msg);
        if (zmq_msg_size(&msg) >= 1 && (data[0] == 0 || data[0] == 1))
            note_subscription(p, &msg);
    }
    zmq_msg_close(&msg);
    update_wanted(p);
}

/* One frame of a message; 0 when it could not be queued (only while delivering the final frame: a normal
   send to a full queue is dropped by ZeroMQ and counts as sent). */
static int send_part(surge_publisher *p, const void *data, size_t bytes, int more)
{
    const int flags = (more ? ZMQ_SNDMORE : 0) | (p->deliver_until_s > 0 ? ZMQ_DONTWAIT : 0);
    for (;;) {
        if (zmq_send(p->socket, data, bytes, flags) >= 0) {
            p->bytes_sent += bytes;
            return 1;
        }
        if (zmq_errno() != EAGAIN || surge_wall_clock_s() > p->deliver_until_s)
            return 0;
        nanosleep(&(struct timespec){.tv_nsec = 1000000}, NULL);
    }
}

/* Topic frame, JSON header frame, then one frame per field. ZeroMQ takes the rest of a message once its
   first frame is queued, so only the first frame can fail. */
static void send_message(surge_publisher *p, const char *topic, cJSON *header, const void *const *arrays,
                         const size_t *array_bytes, int array_count)
{
    char *text = cJSON_PrintUnformatted(header);
    if (!text)
        return;
    if (send_part(p, topic, strlen(topic), 1)) {
        send_part(p, text, strlen(text), array_count > 0);
        for (int i = 0; i < array_count; i++)
            send_part(p, arrays[i], array_bytes[i], i + 1 < array_count);
        p->messages_sent++;
    }
    free(text);
}

/* A double in a header, every bit kept: cJSON's own printing stops at 15 digits where they read back within its
 * tolerance, so a receiver could not match a state's time to a snapshot's. Non-finite values as null. */
static void add_exact_number(cJSON *h, const char *name, double value)
{
    if (!isfinite(value)) {
        cJSON_AddNullToObject(h, name);
        return;
    }
    char text[32];
    snprintf(text, sizeof text, "%.17g", value);
    cJSON_AddRawToObject(h, name, text);
}

static cJSON *common_header(const char *topic, const surge_frame *f)
{
    cJSON *h = cJSON_CreateObject();
    cJSON_AddNumberToObject(h, "schema", SCHEMA_VERSION);
    cJSON_AddStringToObject(h, "topic", topic);
    cJSON_AddNumberToObject(h, "seq", (double)f->sequence);
    cJSON_AddNumberToObject(h, "step", (double)f->diag.step);
    add_exact_number(h, "time_s", f->diag.time_s);
    add_exact_number(h, "dt_s", f->diag.dt_s);
    return h;
}

static void add_field(cJSON *fields, const state_field *field)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "name", field->name);
    cJSON_AddStringToObject(o, "dtype", field->dtype);
    cJSON_AddNumberToObject(o, "components", 1);
    cJSON_AddStringToObject(o, "unit", field->unit);
    cJSON_AddItemToArray(fields, o);
}

static void send_state(surge_publisher *p, const char *topic, const surge_frame *f, const int *indices, int count)
{
    cJSON *h = common_header("state", f);
    cJSON_AddNumberToObject(h, "count", f->snap.count);
    cJSON_AddNumberToObject(h, "dp_m", f->params.numerics.dp_m);
    cJSON_AddNumberToObject(h, "h_m", f->derived.h_m);
    cJSON_AddNumberToObject(h, "domain_length_m", f->params.domain.length_m);
    cJSON_AddNumberToObject(h, "domain_height_m", f->params.domain.height_m);
    cJSON_AddNumberToObject(h, "slope_deg", f->params.body.slope_deg);
    cJSON *fields = cJSON_AddArrayToObject(h, "fields");
    const void *arrays[STATE_FIELD_COUNT];
    size_t bytes[STATE_FIELD_COUNT];
    for (int k = 0; k < count; k++) {
        add_field(fields, &state_fields[indices[k]]);
        arrays[k] = state_field_data(&f->snap, indices[k]);
        bytes[k] = (size_t)f->snap.count * state_fields[indices[k]].element_bytes;
    }
    send_message(p, topic, h, arrays, bytes, count);
    cJSON_Delete(h);
}

static void send_bodies(surge_publisher *p, const surge_frame *f)
{
    const surge_boulder_state *b = &f->snap.boulders;
    cJSON *h = common_header("bodies", f);
    cJSON_AddNumberToObject(h, "count", b->count);
    cJSON *fields = cJSON_AddArrayToObject(h, "fields");
    const void *arrays[BODY_FIELD_COUNT] = {b->x_m, b->y_m, b->angle_rad, b->vx_mps, b->vy_mps, b->omega_radps,
                                            b->radius_m};
    size_t bytes[BODY_FIELD_COUNT];
    static const double none[1] = {0};
    for (int k = 0; k < BODY_FIELD_COUNT; k++) {
        add_field(fields, &body_fields[k]);
        bytes[k] = (size_t)b->count * sizeof(double);
        if (b->count == 0)
            arrays[k] = none;
    }
    send_message(p, "bodies", h, arrays, bytes, BODY_FIELD_COUNT);
    cJSON_Delete(h);
}

static void add_live_parameters(cJSON *h, const surge_params *params)
{
    cJSON *live = cJSON_AddObjectToObject(h, "live");
    for (int i = 0; i < surge_param_count(); i++) {
        const surge_param_info *info = surge_param_at(i);
        if (!info->live)
            continue;
        char name[128], text[64];
        snprintf(name, sizeof name, "%s.%s", info->section, info->key);
        if (info->type == SURGE_PARAM_ENUM) {
            surge_param_format(params, info, text, sizeof text);
            cJSON_AddStringToObject(live, name, text);
        } else if (info->type == SURGE_PARAM_BOOL) {
            cJSON_AddBoolToObject(live, name, surge_param_get_number(params, info) != 0);
        } else {
            cJSON_AddNumberToObject(live, name, surge_param_get_number(params, info));
        }
    }
}

static void send_stats(surge_publisher *p, const surge_frame *f, uint64_t superseded)
{
    cJSON *h = common_header("stats", f);
    cJSON_AddNumberToObject(h, "wall_s", f->wall_s);
    cJSON_AddStringToObject(h, "status", f->final ? "final" : "running");
    cJSON_AddStringToObject(h, "health", surge_health_check_name(f->health));
    cJSON_AddNumberToObject(h, "fluid_count", f->derived.fluid_count);
    cJSON_AddNumberToObject(h, "kinetic_energy_jpm", f->diag.kinetic_energy_jpm);
    cJSON_AddNumberToObject(h, "max_speed_mps", f->diag.max_speed_mps);
    cJSON_AddNumberToObject(h, "max_density_deviation", f->diag.max_density_deviation);
    cJSON_AddNumberToObject(h, "fluid_volume_m2", f->diag.fluid_volume_m2);
    cJSON_AddNumberToObject(h, "mean_vx_mps", f->diag.mean_vx_mps);
    cJSON_AddNumberToObject(h, "belt_speed_mps", f->diag.bottom_wall_speed_mps);
    cJSON_AddNumberToObject(h, "frames_superseded", (double)superseded);
    add_live_parameters(h, &f->params);
    send_message(p, "stats", h, NULL, NULL, 0);
    cJSON_Delete(h);
}

/* The subscribed field subsets, at most SUBSETS_PER_STATE of them, from the one whose turn it is */
static void publish_subsets(surge_publisher *p, const surge_frame *f)
{
    int code = p->subset_turn, sent = 0;
    for (int looked = 0; looked < SUBSET_CODES && sent < p->subset_count && sent < SUBSETS_PER_STATE; looked++) {
        if (p->subsets[code / 64] >> (code % 64) & 1) {
            int indices[STATE_FIELD_COUNT];
            const int count = subset_indices(code, indices);
            char topic[MAX_SUBSCRIPTION_BYTES + 1] = "state/";
            for (int i = 0; i < count; i++)
                strcat(strcat(topic, i ? "," : ""), state_fields[indices[i]].name);
            send_state(p, topic, f, indices, count);
            sent++;
        }
        code = (code + 1) % SUBSET_CODES;
    }
    p->subset_turn = code;
}

static void publish_frame(surge_publisher *p, const surge_frame *f)
{
    if (f->final) {
        const int no_drop = 1;
        zmq_setsockopt(p->socket, ZMQ_XPUB_NODROP, &no_drop, sizeof no_drop);
        p->deliver_until_s = surge_wall_clock_s() + FINAL_DELIVERY_WAIT_S;
    }
    if (subscribed_to(p, "state")) {
        int all[STATE_FIELD_COUNT];
        for (int i = 0; i < STATE_FIELD_COUNT; i++)
            all[i] = i;
        send_state(p, "state", f, all, STATE_FIELD_COUNT);
    }
    publish_subsets(p, f);
    if (subscribed_to(p, "bodies"))
        send_bodies(p, f);
    if (subscribed_to(p, "stats"))
        send_stats(p, f, surge_mailbox_superseded(p->mailbox));
}

void surge_publisher_post_png(surge_publisher *p, const uint8_t *png, size_t png_len, int64_t step, double time_s)
{
    uint8_t *copy = malloc(png_len);
    if (!copy)
        return;
    memcpy(copy, png, png_len);
    pthread_mutex_lock(&p->frame.lock);
    free(p->frame.png);
    p->frame.png = copy;
    p->frame.len = png_len;
    p->frame.step = step;
    p->frame.time_s = time_s;
    p->frame.sequence++;
    p->frame.fresh = 1;
    pthread_mutex_unlock(&p->frame.lock);
}

/* Sends the newest rendered frame, once, as topic "frame": one u8 field holding the PNG file. */
static void publish_png(surge_publisher *p)
{
    pthread_mutex_lock(&p->frame.lock);
    uint8_t *png = p->frame.fresh ? p->frame.png : NULL;
    const size_t len = p->frame.len;
    const int64_t step = p->frame.step;
    const double time_s = p->frame.time_s;
    const uint64_t sequence = p->frame.sequence;
    if (png) {
        p->frame.png = NULL;
        p->frame.fresh = 0;
    }
    pthread_mutex_unlock(&p->frame.lock);
    if (!png)
        return;
    if (subscribed_to(p, "frame")) {
        cJSON *h = cJSON_CreateObject();
        cJSON_AddNumberToObject(h, "schema", SCHEMA_VERSION);
        cJSON_AddStringToObject(h, "topic", "frame");
        cJSON_AddNumberToObject(h, "seq", (double)sequence);
        cJSON_AddNumberToObject(h, "step", (double)step);
        add_exact_number(h, "time_s", time_s);
        cJSON_AddNumberToObject(h, "count", (double)len);
        cJSON *fields = cJSON_AddArrayToObject(h, "fields");
        static const state_field png_field = {"png", "u8", "PNG file", 1};
        add_field(fields, &png_field);
        const void *arrays[1] = {png};
        const size_t bytes[1] = {len};
        send_message(p, "frame", h, arrays, bytes, 1);
        cJSON_Delete(h);
    }
    free(png);
}

static void *publisher_main(void *arg)
{
    surge_publisher *p = arg;
    for (;;) {
        read_subscriptions(p);
        /* read before the take: the final state is posted before `finishing` is set, so a take that comes back
         * empty after `finishing` was seen has nothing left to miss */
        const int finishing = atomic_load(&p->finishing);
        const surge_frame *f = surge_mailbox_take(p->mailbox, 0.02);
        if (f) {
            read_subscriptions(p);
            publish_frame(p, f);
        }
        publish_png(p);
        if (!f && finishing)
            return NULL; /* closed and drained */
    }
}

/* Frees what surge_publisher_start allocated for the subscriptions, and p */
static void free_publisher(surge_publisher *p)
{
    for (int i = 0; i < p->subscriber_count; i++)
        free(p->subscribers[i].subsets);
    free(p->subscribers);
    free(p->subset_holders);
    free(p);
}

surge_publisher *surge_publisher_start(void *context, const surge_publisher_def *def, char *err, size_t err_len)
{
    if (def->every_steps < 1 || !(def->max_rate_hz >= 0) || def->send_hwm < 1) {
        snprintf(err, err_len, "publisher: every_steps and send_hwm must be >= 1 and max_rate_hz >= 0");
        return NULL;
    }
    surge_publisher *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    p->def = *def;
    p->last_step = -1;
    if (!(p->subset_holders = calloc(SUBSET_CODES, sizeof *p->subset_holders))) {
        free_publisher(p);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    pthread_mutex_init(&p->frame.lock, NULL);
    p->socket = zmq_socket(context, ZMQ_XPUB);
    /* connections that never greet are closed after 2 s, subscribers that stop answering heartbeats after 15 s */
    const int linger_ms = 1000, handshake_ms = 2000, heartbeat_ms = 5000, heartbeat_timeout_ms = 15000, every = 1;
    if (!p->socket || zmq_setsockopt(p->socket, ZMQ_SNDHWM, &def->send_hwm, sizeof def->send_hwm) != 0 ||
        zmq_setsockopt(p->socket, ZMQ_XPUB_VERBOSER, &every, sizeof every) != 0 ||
        zmq_setsockopt(p->socket, ZMQ_LINGER, &linger_ms, sizeof linger_ms) != 0 ||
        zmq_setsockopt(p->socket, ZMQ_HANDSHAKE_IVL, &handshake_ms, sizeof handshake_ms) != 0 ||
        zmq_setsockopt(p->socket, ZMQ_HEARTBEAT_IVL, &heartbeat_ms, sizeof heartbeat_ms) != 0 ||
        zmq_setsockopt(p->socket, ZMQ_HEARTBEAT_TIMEOUT, &heartbeat_timeout_ms, sizeof heartbeat_timeout_ms) != 0 ||
        (def->curve && surge_curve_secure_socket(def->curve, p->socket, err, err_len) != 0) ||
        surge_endpoint_bind(p->socket, def->endpoint, "publish on", p->endpoint, err, err_len) != 0) {
        if (p->socket)
            zmq_close(p->socket);
        free_publisher(p);
        return NULL;
    }
    /* subscribers only listen, so they have no idle limit: the cap alone bounds them */
    if (!(p->guard = peer_guard_start(context, p->socket, def->max_peers, 0, err, err_len))) {
        zmq_close(p->socket);
        free_publisher(p);
        return NULL;
    }
    p->mailbox = surge_mailbox_create();
    if (!p->mailbox || pthread_create(&p->thread, NULL, publisher_main, p) != 0) {
        snprintf(err, err_len, "cannot start the publisher thread");
        surge_mailbox_destroy(p->mailbox);
        peer_guard_stop(p->guard);
        zmq_close(p->socket);
        free_publisher(p);
        return NULL;
    }
    p->start_wall_s = surge_wall_clock_s();
    p->last_wall_s = -INFINITY;
    return p;
}

const char *surge_publisher_endpoint(const surge_publisher *p) { return p->endpoint; }

void surge_publisher_offer(surge_publisher *p, const surge_sim *sim)
{
    if (!atomic_load(&p->wanted))
        return;
    const int64_t step = surge_sim_step_count(sim);
    const double now = surge_wall_clock_s();
    /* a parameter changed at this step boundary goes out at once, so that stats show it from its step on */
    const int changed = p->last_step >= 0 && surge_params_live_differ(&p->last_params, surge_sim_params(sim));
    if (!changed && p->last_step >= 0 && step - p->last_step < p->def.every_steps)
        return;
    if (!changed && p->def.max_rate_hz > 0 && now - p->last_wall_s < 1.0 / p->def.max_rate_hz)
        return;
    if (surge_mailbox_post(p->mailbox, sim, now - p->start_wall_s, 0) == 0) {
        p->last_step = step;
        p->last_wall_s = now;
        p->last_params = *surge_sim_params(sim);
    }
}

void surge_publisher_finish(surge_publisher *p, const surge_sim *sim, surge_publisher_report *report)
{
    if (atomic_load(&p->wanted))
        surge_mailbox_post(p->mailbox, sim, surge_wall_clock_s() - p->start_wall_s, 1);
    atomic_store(&p->finishing, 1);
    surge_mailbox_close(p->mailbox);
    pthread_join(p->thread, NULL);
    if (report) {
        report->frames_posted = surge_mailbox_posted(p->mailbox);
        report->frames_superseded = surge_mailbox_superseded(p->mailbox);
        report->messages_sent = p->messages_sent;
        report->bytes_sent = p->bytes_sent;
        long idle;
        peer_guard_counts(p->guard, &report->peers_over_limit, &idle);
    }
    peer_guard_stop(p->guard);
    zmq_close(p->socket);
    surge_mailbox_destroy(p->mailbox);
    free(p->frame.png);
    pthread_mutex_destroy(&p->frame.lock);
    free_publisher(p);
}
