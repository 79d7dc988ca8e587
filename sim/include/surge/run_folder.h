/* What belongs to a run in a folder, so that a new run never overwrites a finished one without being asked: the
 * files surge run writes into its output folder, and the frames a renderer writes. */
#ifndef SURGE_RUN_FOLDER_H
#define SURGE_RUN_FOLDER_H

#include <stddef.h>

/* A file name (no folder) that surge run writes: params.ini, diagnostics.csv, checkpoint.bin, run.pvd,
 * boulders.pvd, control.jsonl, last_good.vtp, last_good.bin, snap_*.vtp, boulders_*.vtp. */
int surge_is_run_file(const char *name);
/* A frame the renderer writes: frame_*.png (and frames.csv, its index). */
int surge_is_frame_file(const char *name);

/* How many files in folder belong (belongs(name) nonzero); 0 for a missing folder. example gets one of their names.
 * -1 with err when the folder exists but cannot be read. */
int surge_folder_count(const char *folder, int (*belongs)(const char *name), char *example, size_t example_len,
                       char *err, size_t err_len);

/* Removes those files (nothing else); returns how many, or -1 with err naming the file that could not go. */
int surge_folder_clear(const char *folder, int (*belongs)(const char *name), char *err, size_t err_len);

#endif
