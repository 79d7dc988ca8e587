/* Control journal: writing applied commands, and replaying them (see surge/journal.h). */
#define _POSIX_C_SOURCE 200809L
#include "surge/journal.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/platform.h"
#include "surge/run.h"

struct surge_journal {
    char *path;
    FILE *file; /* opened at the first entry */
    int failed; /* a write failed: reported once */
};

/* A journal line to keep on restart: one whose "step" is at or before the checkpoint's (or that has none). */
static int entry_at_or_before_step(const char *line, void *resume_step)
{
    const char *member = strstr(line, "\"step\":");
    return !member || strtoll(member + 7, NULL, 10) <= *(const long long *)resume_step;
}

surge_journal *surge_journal_open(const char *path, long long resume_step, char *err, size_t err_len)
{
    surge_journal *j = calloc(1, sizeof *j);
    if (!j || !(j->path = strdup(path))) {
        free(j);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    if (resume_step >= 0 ? surge_file_keep_lines(path, entry_at_or_before_step, &resume_step, err, err_len) != 0
                         : remove(path) != 0 && errno != ENOENT && errno != ENOTDIR) {
        if (resume_step < 0)
            snprintf(err, err_len, "cannot remove the old journal '%s': %s", path, strerror(errno));
        free(j->path);
        free(j);
        return NULL;
    }
    return j;
}

void surge_journal_close(surge_journal *j)
{
    if (!j)
        return;
    if (j->file)
        fclose(j->file);
    free(j->path);
    free(j);
}

int surge_journal_write(surge_journal *j, const surge_sim *sim, const char *source, const char *cmd,
                        const char *key, const char *value, const char *previous)
{
    if (j->failed)
        return -1;
    if (!j->file)
        j->file = fopen(j->path, "a");
    cJSON *entry = cJSON_CreateObject();
    cJSON_AddNumberToObject(entry, "step", (double)surge_sim_step_count(sim));
    cJSON_AddNumberToObject(entry, "time_s", surge_sim_time(sim));
    cJSON_AddStringToObject(entry, "source", source);
    cJSON_AddStringToObject(entry, "cmd", cmd);
    if (key)
        cJSON_AddStringToObject(entry, "key", key);
    if (value)
        cJSON_AddStringToObject(entry, "value", value);
    if (previous)
        cJSON_AddStringToObject(entry, "previous", previous);
    char *line = cJSON_PrintUnformatted(entry);
    cJSON_Delete(entry);
    const int ok = j->file && line && fprintf(j->file, "%s\n", line) > 0 && fflush(j->file) == 0;
    free(line);
    if (!ok) {
        fprintf(stderr, "surge: cannot write the control journal '%s': %s\n", j->path, strerror(errno));
        j->failed = 1;
        return -1;
    }
    return 0;
}

typedef struct replay_entry {
    long long step;
    int stop;    /* a "stop" entry; otherwise a "set" */
    char *key;
    char *value;
    int line;
} replay_entry;

struct surge_replay {
    char *path;
    replay_entry *entries;
    int count;
    int next;
};

void surge_replay_free(surge_replay *r)
{
    if (!r)
        return;
    for (int i = 0; i < r->count; i++) {
        free(r->entries[i].key);
        free(r->entries[i].value);
    }
    free(r->entries);
    free(r->path);
    free(r);
}

/* Parses one journal line into e; 1 when it is an entry to replay, 0 for one with no effect on the state
 * (pause, resume, step, snapshot, checkpoint), -1 with err. */
static int parse_entry(const char *text, replay_entry *e, char *err, size_t err_len)
{
    cJSON *root = cJSON_ParseWithOpts(text, NULL, 1);
    int kept = -1;
    const cJSON *step = cJSON_GetObjectItemCaseSensitive(root, "step");
    const cJSON *cmd = cJSON_GetObjectItemCaseSensitive(root, "cmd");
    const cJSON *key = cJSON_GetObjectItemCaseSensitive(root, "key");
    const cJSON *value = cJSON_GetObjectItemCaseSensitive(root, "value");
    if (!cJSON_IsObject(root))
        snprintf(err, err_len, "not a JSON object");
    else if (!cJSON_IsNumber(step) || !(step->valuedouble >= 0 && step->valuedouble <= 9007199254740992.0) ||
             step->valuedouble != floor(step->valuedouble))
        snprintf(err, err_len, "\"step\" must be a whole number in [0, 2^53]");
    else if (!cJSON_IsString(cmd))
        snprintf(err, err_len, "\"cmd\" must be a string");
    else if (!strcmp(cmd->valuestring, "set") && (!cJSON_IsString(key) || !cJSON_IsString(value)))
        snprintf(err, err_len, "a \"set\" entry needs string \"key\" and \"value\"");
    else {
        e->step = (long long)step->valuedouble;
        e->stop = !strcmp(cmd->valuestring, "stop");
        kept = e->stop || !strcmp(cmd->valuestring, "set");
        if (kept && !e->stop) {
            e->key = strdup(key->valuestring);
            e->value = strdup(value->valuestring);
            if (!e->key || !e->value) {
                snprintf(err, err_len, "out of memory");
                kept = -1;
            }
        }
    }
    cJSON_Delete(root);
    return kept;
}

surge_replay *surge_replay_load(const char *path, char *err, size_t err_len)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        snprintf(err, err_len, "cannot read the journal '%s': %s", path, strerror(errno));
        return NULL;
    }
    surge_replay *r = calloc(1, sizeof *r);
    if (!r || !(r->path = strdup(path))) {
        free(r);
        fclose(f);
        snprintf(err, err_len, "out of memory");
        return NULL;
    }
    char *line = NULL, message[256];
    size_t cap = 0;
    int number = 0, capacity = 0, failed = 0;
    long long last_step = -1;
    while (!failed && getline(&line, &cap, f) != -1) {
        number++;
        if (strspn(line, " \t\r\n") == strlen(line))
            continue;
        replay_entry e = {.line = number};
        const int kept = parse_entry(line, &e, message, sizeof message);
        if (kept < 0) {
            snprintf(err, err_len, "%s:%d: %s", path, number, message);
            failed = 1;
        } else if (kept && e.step < last_step) {
            snprintf(err, err_len, "%s:%d: step %lld comes after step %lld (entries must be in step order)", path,
                     number, e.step, last_step);
            free(e.key);
            free(e.value);
            failed = 1;
        } else if (kept) {
            if (r->count == capacity) {
                const int grown_capacity = capacity ? 2 * capacity : 16;
                replay_entry *grown = realloc(r->entries, (size_t)grown_capacity * sizeof *grown);
                if (!grown) {
                    snprintf(err, err_len, "%s:%d: out of memory", path, number);
                    free(e.key);
                    free(e.value);
                    failed = 1;
                    continue;
                }
                r->entries = grown;
                capacity = grown_capacity;
            }
            r->entries[r->count++] = e;
            last_step = e.step;
        }
    }
    free(line);
    fclose(f);
    if (failed) {
        surge_replay_free(r);
        return NULL;
    }
    return r;
}

int surge_replay_apply(surge_replay *r, surge_sim *sim, surge_journal *journal, char *err, size_t err_len)
{
    const long long step = surge_sim_step_count(sim);
    int requests = SURGE_CONTINUE;
    for (; r->next < r->count && r->entries[r->next].step <= step; r->next++) {
        const replay_entry *e = &r->entries[r->next];
        if (e->step < step) {
            snprintf(err, err_len, "%s:%d: entry for step %lld, but the run is already at step %lld", r->path,
                     e->line, e->step, step);
            return -1;
        }
        if (e->stop) {
            if (journal)
                surge_journal_write(journal, sim, "replay", "stop", NULL, NULL, NULL);
            requests |= SURGE_REQUEST_STOP;
            continue;
        }
        char previous[64], message[512];
        const surge_param_info *info = surge_param_find(e->key);
        if (info)
            surge_param_format(surge_sim_params(sim), info, previous, sizeof previous);
        if (surge_sim_set_param(sim, e->key, e->value, message, sizeof message) != 0) {
            snprintf(err, err_len, "%s:%d: %s", r->path, e->line, message);
            return -1;
        }
        if (journal)
            surge_journal_write(journal, sim, "replay", "set", e->key, e->value, previous);
    }
    return requests;
}
