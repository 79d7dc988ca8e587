/* Where a run's and a rendering's outputs go, and the refusal to write over earlier ones unless asked. */
#define _XOPEN_SOURCE 700 /* POSIX 2008 and realpath */
#include "cli.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "surge/run_folder.h"

/* runs/<case file name without folder and extension> */
void default_output_dir(const char *case_path, char *out, size_t len)
{
    const char *base = case_path ? strrchr(case_path, '/') : NULL;
    base = base ? base + 1 : (case_path ? case_path : "demo.ini");
    size_t n = strcspn(base, ".");
    snprintf(out, len, "runs/%.*s", (int)n, base);
}

/* Refuses (-1) to write into a folder that holds earlier outputs (belongs) unless --overwrite, which removes them;
 * what names the outputs and hint says how else to go on. */
int claim_folder(const char *folder, int (*belongs)(const char *name), int overwrite, const char *what,
                 const char *hint)
{
    char example[256], err[1024];
    const int count = surge_folder_count(folder, belongs, example, sizeof example, err, sizeof err);
    if (count < 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    if (count == 0)
        return 0;
    if (!overwrite) {
        fprintf(stderr, "surge: %s already holds %s (%d files, e.g. %s); nothing was written. %s, or add --overwrite "
                        "to replace them\n", folder, what, count, example, hint);
        return -1;
    }
    const int removed = surge_folder_clear(folder, belongs, err, sizeof err);
    if (removed < 0) {
        fprintf(stderr, "surge: --overwrite: %s\n", err);
        return -1;
    }
    fprintf(stderr, "surge: --overwrite: removed %d files of %s from %s\n", removed, what, folder);
    return 0;
}

/* The default output folder, or the first of folder-2, folder-3, ... that holds no earlier run. */
int fresh_default_folder(char *folder, size_t len)
{
    char base[4096], err[1024];
    snprintf(base, sizeof base, "%s", folder);
    for (int n = 1; n < 10000; n++) {
        if (n > 1 && snprintf(folder, len, "%s-%d", base, n) >= (int)len) {
            fprintf(stderr, "surge: the output folder name %s is too long\n", base);
            return -1;
        }
        const int count = surge_folder_count(folder, surge_is_run_file, NULL, 0, err, sizeof err);
        if (count < 0) {
            fprintf(stderr, "surge: %s\n", err);
            return -1;
        }
        if (count == 0) {
            if (n > 1)
                fprintf(stderr, "surge: %s holds an earlier run; this one goes to %s (-o chooses the folder, "
                                "--overwrite replaces)\n", base, folder);
            return 0;
        }
    }
    fprintf(stderr, "surge: %s-2 ... %s-9999 all hold runs; choose a folder with -o\n", base, base);
    return -1;
}

/* Whether two paths name the same existing folder. */
int same_folder(const char *a, const char *b)
{
    char ra[PATH_MAX], rb[PATH_MAX];
    return realpath(a, ra) && realpath(b, rb) && !strcmp(ra, rb);
}

/* The folder part of a file path ("." when it has none). */
void folder_of(const char *path, char *folder, size_t len)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(folder, len, ".");
    else
        snprintf(folder, len, "%.*s", slash == path ? 1 : (int)(slash - path), path);
}

/* A movie file's folder must exist and be writable before the run starts, not when the first frame is encoded;
 * and, unless replacing is allowed, no movie may be there already. 0, or -1 with the message printed. */
int claim_movie(const char *movie_path, int may_replace)
{
    char folder[4096];
    folder_of(movie_path, folder, sizeof folder);
    if (access(folder, W_OK) != 0) {
        fprintf(stderr, "surge: --movie %s: its folder %s %s\n", movie_path, folder,
                errno == ENOENT ? "does not exist" : "is not writable");
        return -1;
    }
    if (!may_replace && access(movie_path, F_OK) == 0) {
        fprintf(stderr, "surge: the movie %s exists; nothing was written. Choose another --movie file, or add "
                        "--overwrite to replace it\n", movie_path);
        return -1;
    }
    return 0;
}
