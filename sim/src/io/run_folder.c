/* Which files in a folder belong to a run or to its frames, counted and cleared (surge/run_folder.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/run_folder.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

static int has_affixes(const char *name, const char *prefix, const char *suffix)
{
    const size_t n = strlen(name), p = strlen(prefix), s = strlen(suffix);
    return n > p + s && !strncmp(name, prefix, p) && !strcmp(name + n - s, suffix);
}

int surge_is_run_file(const char *name)
{
    static const char *const fixed[] = {"params.ini", "diagnostics.csv", "checkpoint.bin", "run.pvd", "boulders.pvd",
                                        "control.jsonl", "last_good.vtp", "last_good.bin", "boulders.csv", "flow.csv"};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (!strcmp(name, fixed[i]))
            return 1;
    return has_affixes(name, "snap_", ".vtp") || has_affixes(name, "boulders_", ".vtp");
}

int surge_is_frame_file(const char *name)
{
    return has_affixes(name, "frame_", ".png") || !strcmp(name, "frames.csv");
}

/* Calls visit for each belonging file; stops at the first nonzero return. -1 when the folder cannot be read. */
static int each_file(const char *folder, int (*belongs)(const char *name),
                     int (*visit)(const char *folder, const char *name, void *context), void *context, char *err,
                     size_t err_len)
{
    DIR *dir = opendir(folder);
    if (!dir) {
        if (errno == ENOENT || errno == ENOTDIR) /* nothing there yet (making the folder reports the rest) */
            return 0;
        snprintf(err, err_len, "cannot read the folder '%.900s': %s", folder, strerror(errno));
        return -1;
    }
    int rc = 0;
    for (struct dirent *e; rc == 0 && (e = readdir(dir)) != NULL;)
        if (belongs(e->d_name))
            rc = visit(folder, e->d_name, context);
    closedir(dir);
    return rc;
}

typedef struct tally {
    int count;
    char *example;
    size_t example_len;
    char *err;
    size_t err_len;
} tally;

static int count_one(const char *folder, const char *name, void *context)
{
    (void)folder;
    tally *t = context;
    if (t->count++ == 0 && t->example_len > 0)
        snprintf(t->example, t->example_len, "%s", name);
    return 0;
}

int surge_folder_count(const char *folder, int (*belongs)(const char *name), char *example, size_t example_len,
                       char *err, size_t err_len)
{
    tally t = {0, example, example_len, err, err_len};
    if (example_len > 0)
        example[0] = '\0';
    return each_file(folder, belongs, count_one, &t, err, err_len) < 0 ? -1 : t.count;
}

static int remove_one(const char *folder, const char *name, void *context)
{
    tally *t = context;
    char path[4200];
    snprintf(path, sizeof path, "%s/%s", folder, name);
    if (unlink(path) != 0) {
        snprintf(t->err, t->err_len, "cannot remove '%.900s': %s", path, strerror(errno));
        return -1;
    }
    t->count++;
    return 0;
}

int surge_folder_clear(const char *folder, int (*belongs)(const char *name), char *err, size_t err_len)
{
    /* removing while reading a folder may skip entries: repeat until none is left */
    tally t = {0, NULL, 0, err, err_len};
    for (int pass = 0; pass < 4; pass++) {
        const int before = t.count;
        if (each_file(folder, belongs, remove_one, &t, err, err_len) != 0)
            return -1;
        if (t.count == before)
            break;
    }
    return t.count;
}
