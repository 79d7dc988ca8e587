/* CURVE keys and the ZAP handler that admits only allowed clients and numbers every connection it admits (see
 * surge/curve.h; ZeroMQ RFC 26 and 27). */
#define _POSIX_C_SOURCE 200809L
#include "surge/curve.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zmq.h>

enum {
    KEY_BYTES = 32,
    Z85_CHARS = 40,
    MAX_KEY_FILE_BYTES = 65536,
    MAX_ALLOWED_KEYS = 4096,
    ZAP_POLL_MS = 100,
    REFUSALS_REPORTED = 5, /* the first refusals are printed, later ones only counted */
};
static const char ZAP_ENDPOINT[] = "inproc://zeromq.zap.01"; /* fixed by RFC 27 */
static const char ZAP_DOMAIN[] = "surge";

struct surge_curve_server {
    int secure; /* 0: no keys, the handler admits plain (NULL) connections and only numbers them */
    char secret_z85[SURGE_CURVE_KEY_Z85_BYTES];
    uint8_t (*allowed)[KEY_BYTES];
    int allowed_count;
    uint64_t admitted; /* connections admitted so far: the last one's number (handler thread) */
    void *zap_socket; /* REP, used by the handler thread only once it runs */
    pthread_t thread;
    int thread_started;
    atomic_int stop;
    atomic_long refused;
};

/* ---- key files ---- */

int surge_curve_write_key_pair(const char *name, char *err, size_t err_len)
{
    char public_z85[SURGE_CURVE_KEY_Z85_BYTES], secret_z85[SURGE_CURVE_KEY_Z85_BYTES];
    if (zmq_curve_keypair(public_z85, secret_z85) != 0) {
        snprintf(err, err_len, "cannot make a CURVE key pair: %s (libzmq built without CURVE?)",
                 zmq_strerror(zmq_errno()));
        return -1;
    }
    char paths[2][4096];
    const char *suffix[2] = {".pub", ".key"};
    for (int k = 0; k < 2; k++) {
        if ((size_t)snprintf(paths[k], sizeof paths[k], "%s%s", name, suffix[k]) >= sizeof paths[k]) {
            snprintf(err, err_len, "key name '%s' is too long", name);
            return -1;
        }
        struct stat st;
        if (lstat(paths[k], &st) == 0) {
            snprintf(err, err_len, "%s already exists; nothing written (remove it first to replace the keys)", paths[k]);
            return -1;
        }
    }
    for (int k = 0; k < 2; k++) {
        const int secret = k == 1;
        const int fd = open(paths[k], O_WRONLY | O_CREAT | O_EXCL, secret ? 0600 : 0644);
        FILE *f = fd >= 0 ? fdopen(fd, "w") : NULL;
        if (!f) {
            snprintf(err, err_len, "cannot create %s: %s", paths[k], strerror(errno));
            if (fd >= 0)
                close(fd);
            if (secret)
                remove(paths[0]);
            return -1;
        }
        fprintf(f, "#   ZeroMQ CURVE %s certificate, made by surge keygen\n", secret ? "**secret**" : "public");
        fprintf(f, secret ? "#   Keep this file private: whoever holds it can act as its owner.\n"
                          : "#   Give this file to the peers that must recognise its owner.\n");
        fprintf(f, "\nmetadata\ncurve\n    public-key = \"%s\"\n", public_z85);
        if (secret)
            fprintf(f, "    secret-key = \"%s\"\n", secret_z85);
        if (fclose(f) != 0) {
            snprintf(err, err_len, "cannot write %s: %s", paths[k], strerror(errno));
            remove(paths[0]);
            if (secret)
                remove(paths[1]);
            return -1;
        }
    }
    return 0;
}

/* `name = "value"` on a trimmed line: copies the value (at most Z85_CHARS + 1 characters) into out.
 * 1 when the line is that name's, 0 when it is not, -1 when it is but malformed. */
static int key_line(const char *line, const char *name, char *out)
{
    const size_t n = strlen(name);
    if (strncmp(line, name, n) != 0)
        return 0;
    const char *p = line + n;
    while (*p == ' ' || *p == '\t')
        p++;
    if (*p++ != '=')
        return -1;
    while (*p == ' ' || *p == '\t')
        p++;
    if (*p++ != '"')
        return -1;
    const char *end = strchr(p, '"');
    if (!end || (size_t)(end - p) != Z85_CHARS)
        return -1;
    for (const char *q = end + 1; *q; q++)
        if (*q != ' ' && *q != '\t' && *q != '\r')
            return -1;
    memcpy(out, p, Z85_CHARS);
    out[Z85_CHARS] = '\0';
    uint8_t decoded[KEY_BYTES];
    return zmq_z85_decode(decoded, out) ? 1 : -1;
}

int surge_curve_read_key_file(const char *path, char public_z85[SURGE_CURVE_KEY_Z85_BYTES],
                              char secret_z85[SURGE_CURVE_KEY_Z85_BYTES], char *err, size_t err_len)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(err, err_len, "cannot read key file %s: %s", path, strerror(errno));
        return -1;
    }
    if (!S_ISREG(st.st_mode) || st.st_size > MAX_KEY_FILE_BYTES) {
        snprintf(err, err_len, "%s is not a key file (%s)", path,
                 S_ISREG(st.st_mode) ? "larger than 64 KiB" : "not a regular file");
        return -1;
    }
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, err_len, "cannot read key file %s: %s", path, strerror(errno));
        return -1;
    }
    char line[512], public_found[SURGE_CURVE_KEY_Z85_BYTES] = "", secret_found[SURGE_CURVE_KEY_Z85_BYTES] = "";
    int line_number = 0, rc = 0;
    while (rc == 0 && fgets(line, sizeof line, f)) {
        line_number++;
        char *s = line;
        while (*s == ' ' || *s == '\t')
            s++;
        s[strcspn(s, "\n")] = '\0';
        const char *names[2] = {"public-key", "secret-key"};
        char *found[2] = {public_found, secret_found};
        for (int k = 0; k < 2 && rc == 0; k++) {
            char value[SURGE_CURVE_KEY_Z85_BYTES + 1];
            const int got = key_line(s, names[k], value);
            if (got < 0 || (got == 1 && found[k][0])) {
                snprintf(err, err_len, "%s line %d: %s", path, line_number,
                         got < 0 ? "a key must read name = \"40 Z85 characters\"" : "the key is given twice");
                rc = -1;
            } else if (got == 1) {
                memcpy(found[k], value, SURGE_CURVE_KEY_Z85_BYTES);
            }
        }
    }
    fclose(f);
    if (rc != 0)
        return -1;
    if (!public_found[0] || (secret_z85 && !secret_found[0])) {
        snprintf(err, err_len, "%s holds no %s (expected a line public-key = \"...\"%s; `surge keygen NAME` makes key files)",
                 path, !public_found[0] ? "public-key" : "secret-key: give the .key file, not the .pub",
                 secret_z85 ? " and a line secret-key = \"...\"" : "");
        return -1;
    }
    memcpy(public_z85, public_found, SURGE_CURVE_KEY_Z85_BYTES);
    if (secret_z85)
        memcpy(secret_z85, secret_found, SURGE_CURVE_KEY_Z85_BYTES);
    return 0;
}

/* ---- the allow-list ---- */

static int allow_key_file(surge_curve_server *s, const char *path, char *err, size_t err_len)
{
    char public_z85[SURGE_CURVE_KEY_Z85_BYTES];
    if (surge_curve_read_key_file(path, public_z85, NULL, err, err_len) != 0)
        return -1;
    if (s->allowed_count == MAX_ALLOWED_KEYS) {
        snprintf(err, err_len, "more than %d client keys in the allow-list", MAX_ALLOWED_KEYS);
        return -1;
    }
    zmq_z85_decode(s->allowed[s->allowed_count++], public_z85);
    return 0;
}

static int ends_with(const char *s, const char *suffix)
{
    const size_t n = strlen(s), m = strlen(suffix);
    return n > m && !strcmp(s + n - m, suffix);
}

static int read_allow_list(surge_curve_server *s, const char *path, char *err, size_t err_len)
{
    s->allowed = malloc(sizeof *s->allowed * MAX_ALLOWED_KEYS);
    if (!s->allowed) {
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    struct stat st;
    if (stat(path, &st) != 0) {
        snprintf(err, err_len, "cannot read the client keys %s: %s", path, strerror(errno));
        return -1;
    }
    if (!S_ISDIR(st.st_mode))
        return allow_key_file(s, path, err, err_len);
    DIR *dir = opendir(path);
    if (!dir) {
        snprintf(err, err_len, "cannot read the client key folder %s: %s", path, strerror(errno));
        return -1;
    }
    int rc = 0;
    for (struct dirent *e; rc == 0 && (e = readdir(dir));) {
        if (!ends_with(e->d_name, ".pub"))
            continue;
        char file[4608];
        snprintf(file, sizeof file, "%s/%s", path, e->d_name);
        rc = allow_key_file(s, file, err, err_len);
    }
    closedir(dir);
    if (rc == 0 && s->allowed_count == 0) {
        snprintf(err, err_len, "the client key folder %s holds no *.pub file: no client could connect", path);
        rc = -1;
    }
    return rc;
}

/* ---- the ZAP handler (RFC 27) ---- */

static int is_allowed(const surge_curve_server *s, const uint8_t *key)
{
    for (int k = 0; k < s->allowed_count; k++)
        if (!memcmp(s->allowed[k], key, KEY_BYTES))
            return 1;
    return 0;
}

/* Answers one request: frames version, request id, domain, address, routing id, mechanism, credentials (one frame,
 * the client's key, for CURVE; none for NULL). A secured handler admits CURVE clients with an allowed key, an open
 * one plain (NULL) connections; each admitted connection gets the next number as its User-Id. */
static void answer_zap_request(surge_curve_server *s)
{
    enum { FRAMES = 7 };
    zmq_msg_t frame[FRAMES];
    int count = 0, more = 1; /* frames received; those past FRAMES are read and dropped */
    while (more) {
        zmq_msg_t scratch, *m = count < FRAMES ? &frame[count] : &scratch;
        zmq_msg_init(m);
        if (zmq_msg_recv(m, s->zap_socket, 0) < 0) {
            zmq_msg_close(m);
            break;
        }
        more = zmq_msg_more(m);
        if (count++ >= FRAMES)
            zmq_msg_close(m);
    }
    const int frames_kept = count < FRAMES ? count : FRAMES;
    const int version_ok = count >= 6 && zmq_msg_size(&frame[0]) == 3 && !memcmp(zmq_msg_data(&frame[0]), "1.0", 3);
    const int well_formed = version_ok && count == FRAMES && zmq_msg_size(&frame[5]) == 5 &&
                            !memcmp(zmq_msg_data(&frame[5]), "CURVE", 5) && zmq_msg_size(&frame[6]) == KEY_BYTES;
    const int plain = version_ok && count == 6 && zmq_msg_size(&frame[5]) == 4 &&
                      !memcmp(zmq_msg_data(&frame[5]), "NULL", 4);
    const int admit = s->secure ? well_formed && is_allowed(s, zmq_msg_data(&frame[6])) : plain;
    if (!admit && s->secure) {
        const long refused = atomic_fetch_add(&s->refused, 1) + 1;
        if (refused <= REFUSALS_REPORTED) {
            char key_z85[SURGE_CURVE_KEY_Z85_BYTES] = "?", address[64] = "?";
            if (well_formed) {
                zmq_z85_encode(key_z85, zmq_msg_data(&frame[6]), KEY_BYTES);
                const size_t n = zmq_msg_size(&frame[3]) < sizeof address - 1 ? zmq_msg_size(&frame[3]) : sizeof address - 1;
                memcpy(address, zmq_msg_data(&frame[3]), n);
                address[n] = '\0';
                for (char *c = address; *c; c++)
                    if (*c < 0x20 || *c > 0x7e)
                        *c = '?';
            }
            fprintf(stderr, "surge: refused a connection from %s: client key \"%s\" is not in the allow-list%s\n", address,
                    key_z85, refused == REFUSALS_REPORTED ? " (further refusals are only counted)" : "");
        }
    }
    /* reply (a REP socket must answer every request): version, request id, status, status text, user id,
     * metadata */
    const char *text = admit ? "OK" : s->secure ? "client key not allowed" : "only plain connections here";
    char user_id[24] = "";
    if (admit)
        snprintf(user_id, sizeof user_id, "%" PRIu64, ++s->admitted);
    zmq_send(s->zap_socket, "1.0", 3, ZMQ_SNDMORE);
    zmq_send(s->zap_socket, count >= 2 ? zmq_msg_data(&frame[1]) : "", count >= 2 ? zmq_msg_size(&frame[1]) : 0,
             ZMQ_SNDMORE);
    zmq_send(s->zap_socket, admit ? "200" : "400", 3, ZMQ_SNDMORE);
    zmq_send(s->zap_socket, text, strlen(text), ZMQ_SNDMORE);
    zmq_send(s->zap_socket, user_id, strlen(user_id), ZMQ_SNDMORE);
    zmq_send(s->zap_socket, "", 0, 0);
    for (int k = 0; k < frames_kept; k++)
        zmq_msg_close(&frame[k]);
}

static void *zap_main(void *arg)
{
    surge_curve_server *s = arg;
    while (!atomic_load(&s->stop)) {
        zmq_pollitem_t item = {.socket = s->zap_socket, .events = ZMQ_POLLIN};
        const int ready = zmq_poll(&item, 1, ZAP_POLL_MS);
        if (ready < 0 && zmq_errno() == ETERM)
            break;
        if (ready > 0)
            answer_zap_request(s);
    }
    return NULL;
}

/* Binds the ZAP endpoint and starts the handler thread; 0, or -1 with err (s is then stopped and freed) */
static int start_handler(void *context, surge_curve_server *s, char *err, size_t err_len)
{
    const int linger_ms = 0;
    s->zap_socket = zmq_socket(context, ZMQ_REP);
    if (!s->zap_socket || zmq_setsockopt(s->zap_socket, ZMQ_LINGER, &linger_ms, sizeof linger_ms) != 0 ||
        zmq_bind(s->zap_socket, ZAP_ENDPOINT) != 0) {
        snprintf(err, err_len, "cannot start the CURVE client check (%s): %s", ZAP_ENDPOINT, zmq_strerror(zmq_errno()));
        surge_curve_server_stop(s);
        return -1;
    }
    if (pthread_create(&s->thread, NULL, zap_main, s) != 0) {
        snprintf(err, err_len, "cannot start the CURVE client check thread");
        surge_curve_server_stop(s);
        return -1;
    }
    s->thread_started = 1;
    return 0;
}

surge_curve_server *surge_curve_server_start(void *context, const char *server_key_path,
                                             const char *allowed_clients_path, char *err, size_t err_len)
{
    if (!zmq_has("curve")) {
        snprintf(err, err_len, "this libzmq was built without CURVE security");
        return NULL;
    }
    surge_curve_server *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    s->secure = 1;
    char public_z85[SURGE_CURVE_KEY_Z85_BYTES];
    if (surge_curve_read_key_file(server_key_path, public_z85, s->secret_z85, err, err_len) != 0 ||
        read_allow_list(s, allowed_clients_path, err, err_len) != 0) {
        surge_curve_server_stop(s);
        return NULL;
    }
    return start_handler(context, s, err, err_len) == 0 ? s : NULL;
}

surge_curve_server *surge_curve_numbering_start(void *context, char *err, size_t err_len)
{
    surge_curve_server *s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    return start_handler(context, s, err, err_len) == 0 ? s : NULL;
}

int surge_curve_secure_socket(const surge_curve_server *s, void *socket, char *err, size_t err_len)
{
    const int as_server = 1;
    if (zmq_setsockopt(socket, ZMQ_ZAP_DOMAIN, ZAP_DOMAIN, strlen(ZAP_DOMAIN)) != 0 ||
        (s->secure && (zmq_setsockopt(socket, ZMQ_CURVE_SERVER, &as_server, sizeof as_server) != 0 ||
                       zmq_setsockopt(socket, ZMQ_CURVE_SECRETKEY, s->secret_z85, Z85_CHARS) != 0))) {
        snprintf(err, err_len, "cannot make the socket a %s: %s", s->secure ? "CURVE server" : "numbered socket",
                 zmq_strerror(zmq_errno()));
        return -1;
    }
    return 0;
}

int surge_curve_allowed_count(const surge_curve_server *s)
{
    return s->allowed_count;
}

long surge_curve_refused_count(const surge_curve_server *s)
{
    return atomic_load(&s->refused);
}

void surge_curve_server_stop(surge_curve_server *s)
{
    if (!s)
        return;
    if (s->thread_started) {
        atomic_store(&s->stop, 1);
        pthread_join(s->thread, NULL);
    }
    if (s->zap_socket)
        zmq_close(s->zap_socket);
    free(s->allowed);
    memset(s->secret_z85, 0, sizeof s->secret_z85);
    free(s);
}
