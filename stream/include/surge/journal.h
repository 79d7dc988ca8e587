/* The control journal: every command applied to a running simulation, with the step and time it applied at,
 * one JSON object per line (control.jsonl in the run's output folder; docs/protocol.md). Replaying a journal
 * applies its parameter changes and its stop after the same steps, so a steered run is reproduced bit for bit. */
#ifndef SURGE_JOURNAL_H
#define SURGE_JOURNAL_H

#include <stddef.h>

#include "surge/sim.h"

typedef struct surge_journal surge_journal;

/* The file is created at the first entry. A run restarted from a checkpoint of step resume_step keeps the existing
 * journal's entries up to that step (later ones belong to the interrupted run's lost continuation) and appends;
 * a fresh run (resume_step < 0) removes an old journal at path now. NULL with the reason in err. */
surge_journal *surge_journal_open(const char *path, long long resume_step, char *err, size_t err_len);
void surge_journal_close(surge_journal *journal);

/* Appends {"step", "time_s", "source", "cmd"[, "key", "value", "previous"]} (NULL members are left out) and
 * flushes it. Returns 0, or -1 when the file cannot be written (reported once on stderr). */
int surge_journal_write(surge_journal *journal, const surge_sim *sim, const char *source, const char *cmd,
                        const char *key, const char *value, const char *previous);

typedef struct surge_replay surge_replay;

/* Reads a journal; errors name path:line. */
surge_replay *surge_replay_load(const char *path, char *err, size_t err_len);
void surge_replay_free(surge_replay *replay);

/* At a step boundary: applies the journal's "set" and "stop" entries of the current step, in order, and
 * journals them (journal may be NULL). Returns SURGE_CONTINUE or SURGE_REQUEST_STOP (surge/run.h), or -1 with
 * the reason in err (a change that no longer applies, an entry for a step already passed). */
int surge_replay_apply(surge_replay *replay, surge_sim *sim, surge_journal *journal, char *err, size_t err_len);

#endif
