/* Operating-system helpers (see surge/platform.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/platform.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

double surge_wall_clock_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
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
