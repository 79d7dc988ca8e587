/* Small operating-system helpers shared by the solver's outputs, the stream, the renderer and the tools. */
#ifndef SURGE_PLATFORM_H
#define SURGE_PLATFORM_H

#include <stddef.h>
#include <stdio.h>

/* Seconds on a monotonic clock (for rates and cadences, not dates). */
double surge_wall_clock_s(void);

/* Creates path and its missing parents (mkdir -p). Returns 0, or -1 with err naming the folder that could not be
 * created or the path that is not a folder; what names the folder in the message ("output", "frames"). */
int surge_make_folders(const char *path, const char *what, char *err, size_t err_len);

/* Rewrites the text file at path keeping only the lines (without their newline) for which keep(line, context) is
 * nonzero; a missing file is no error. A restart uses it to drop what the interrupted run wrote after the checkpoint
 * it resumes from. Returns 0, or -1 with err naming the file. */
int surge_file_keep_lines(const char *path, int (*keep)(const char *line, void *context), void *context, char *err,
                          size_t err_len);

/* fopen that waits out a momentary shortage of file descriptors: while open fails with EMFILE or ENFILE it
 * retries every 10 ms for up to 2 s (other threads of the process, such as sockets' I/O threads, may hold
 * descriptors for a moment: a burst of connections that is being turned away). Otherwise as fopen. */
FILE *surge_fopen_waiting(const char *path, const char *mode);

/* Raises the soft limit on open files to the hard limit; returns the soft limit now in force (-1: unknown). */
long surge_raise_file_limit(void);

/* The program that is running: "surge COMMIT, COMPILER VERSION, vectors EXTENSIONS" (the source's git commit at the
 * build, with "-dirty.HASH" if it had changes, HASH a short hash of them, "unknown" without git: tools/
 * build_commit.cmake; the widest vector extensions it was compiled for, which set the pair loops' speed and, through
 * their lane count, the state hash: docs/performance.md). */
const char *surge_build_description(void);

/* The machine it runs on, into buf: the CPU's model name, its x86 family and model, the processors online and
 * whether the CPU has AVX2 and AVX-512 (from /proc/cpuinfo; "unknown CPU" where that does not say). Timings are
 * comparable only on the same CPU (docs/performance.md, "Comparing timings"). */
void surge_machine_description(char *buf, size_t len);

#endif
