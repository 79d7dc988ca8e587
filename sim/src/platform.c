/* Operating-system helpers (see surge/platform.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/platform.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "surge_build_commit.h"

double surge_wall_clock_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

FILE *surge_fopen_waiting(const char *path, const char *mode)
{
    for (int attempt = 0;; attempt++) {
        FILE *f = fopen(path, mode);
        if (f || (errno != EMFILE && errno != ENFILE) || attempt == 200)
            return f;
        const struct timespec wait = {.tv_sec = 0, .tv_nsec = 10000000};
        nanosleep(&wait, NULL);
    }
}

long surge_raise_file_limit(void)
{
    struct rlimit limit;
    if (getrlimit(RLIMIT_NOFILE, &limit) != 0)
        return -1;
    if (limit.rlim_cur < limit.rlim_max) {
        limit.rlim_cur = limit.rlim_max;
        if (setrlimit(RLIMIT_NOFILE, &limit) != 0)
            getrlimit(RLIMIT_NOFILE, &limit);
    }
    return limit.rlim_cur == RLIM_INFINITY ? -1 : (long)limit.rlim_cur;
}

int surge_make_folders(const char *path, const char *what, char *err, size_t err_len)
{
    char buf[4096];
    if (path[0] == '\0') {
        snprintf(err, err_len, "%s folder name is empty", what);
        return -1;
    }
    if (snprintf(buf, sizeof buf, "%s", path) >= (int)sizeof buf) {
        snprintf(err, err_len, "%s folder name too long", what);
        return -1;
    }
    for (char *p = buf + 1;; p++) {
        if (*p == '/' || *p == '\0') {
            const char saved = *p;
            *p = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
                snprintf(err, err_len, "cannot create %s folder '%s': %s", what, buf, strerror(errno));
                return -1;
            }
            *p = saved;
            if (saved == '\0')
                break;
        }
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode)) {
        snprintf(err, err_len, "%s path '%s' is not a folder", what, path);
        return -1;
    }
    return 0;
}

int surge_file_keep_lines(const char *path, int (*keep)(const char *line, void *context), void *context, char *err,
                          size_t err_len)
{
    FILE *in = fopen(path, "r");
    if (!in) {
        if (errno == ENOENT)
            return 0;
        snprintf(err, err_len, "cannot read '%s': %s", path, strerror(errno));
        return -1;
    }
    char tmp[4200];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *out = fopen(tmp, "w");
    if (!out) {
        snprintf(err, err_len, "cannot write '%s': %s", tmp, strerror(errno));
        fclose(in);
        return -1;
    }
    char *line = NULL;
    size_t capacity = 0;
    ssize_t len;
    int ok = 1;
    while (ok && (len = getline(&line, &capacity, in)) >= 0) {
        const int had_newline = len > 0 && line[len - 1] == '\n';
        if (had_newline)
            line[len - 1] = '\0';
        if (keep(line, context))
            ok = fprintf(out, "%s%s", line, had_newline ? "\n" : "") >= 0;
    }
    ok = ok && !ferror(in);
    free(line);
    fclose(in);
    if (fclose(out) != 0 || !ok || rename(tmp, path) != 0) {
        snprintf(err, err_len, "cannot rewrite '%s': %s", path, strerror(errno));
        remove(tmp);
        return -1;
    }
    return 0;
}

#if defined(__clang__)
#define SURGE_COMPILER "clang " __clang_version__
#elif defined(__GNUC__)
#define SURGE_COMPILER "gcc " __VERSION__
#else
#define SURGE_COMPILER "an unnamed C compiler"
#endif

#if defined(__AVX512F__)
#define SURGE_VECTORS "AVX-512"
#elif defined(__AVX2__) && defined(__FMA__)
#define SURGE_VECTORS "AVX2 and FMA"
#elif defined(__AVX2__)
#define SURGE_VECTORS "AVX2"
#elif defined(__AVX__)
#define SURGE_VECTORS "AVX"
#elif defined(__SSE2__)
#define SURGE_VECTORS "SSE2"
#elif defined(__ARM_NEON)
#define SURGE_VECTORS "NEON"
#else
#define SURGE_VECTORS "none named"
#endif

const char *surge_build_description(void)
{
    return "surge " SURGE_VERSION SURGE_BUILD_SUFFIX ", " SURGE_COMPILER ", vectors " SURGE_VECTORS;
}

/* The value of "key<spaces>: value" in line, or NULL */
static const char *cpuinfo_value(const char *line, const char *key)
{
    const size_t n = strlen(key);
    if (strncmp(line, key, n) != 0)
        return NULL;
    line += n;
    while (*line == ' ' || *line == '\t')
        line++;
    if (*line != ':')
        return NULL;
    line++;
    while (*line == ' ')
        line++;
    return line;
}

/* Whether the space-separated list flags holds the word flag */
static int has_flag(const char *flags, const char *flag)
{
    const size_t n = strlen(flag);
    for (const char *p = flags; (p = strstr(p, flag)) != NULL; p += n)
        if ((p == flags || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\n' || p[n] == '\0'))
            return 1;
    return 0;
}

void surge_machine_description(char *buf, size_t len)
{
    char model_name[256] = "unknown CPU", family[32] = "", model[32] = "", line[8192];
    int avx2 = -1, avx512 = -1; /* -1: the CPU's flags not read */
    FILE *f = fopen("/proc/cpuinfo", "r");
    while (f && fgets(line, sizeof line, f) && line[0] != '\n') { /* the first processor's block */
        const char *v;
        if ((v = cpuinfo_value(line, "model name")) != NULL)
            snprintf(model_name, sizeof model_name, "%.*s", (int)strcspn(v, "\n"), v);
        else if ((v = cpuinfo_value(line, "cpu family")) != NULL)
            snprintf(family, sizeof family, "%.*s", (int)strcspn(v, "\n"), v);
        else if ((v = cpuinfo_value(line, "model")) != NULL)
            snprintf(model, sizeof model, "%.*s", (int)strcspn(v, "\n"), v);
        else if ((v = cpuinfo_value(line, "flags")) != NULL)
            avx2 = has_flag(v, "avx2"), avx512 = has_flag(v, "avx512f");
    }
    if (f)
        fclose(f);
    const long processors = sysconf(_SC_NPROCESSORS_ONLN);
    char identity[96] = "", online[48] = "";
    if (family[0] && model[0])
        snprintf(identity, sizeof identity, ", x86 family %s model %s", family, model);
    if (processors > 0)
        snprintf(online, sizeof online, ", %ld processors online", processors);
    snprintf(buf, len, "%s%s%s%s%s", model_name, identity, online,
             avx2 < 0 ? "" : avx2 ? ", AVX2" : ", no AVX2", avx512 < 0 ? "" : avx512 ? ", AVX-512" : ", no AVX-512");
}
