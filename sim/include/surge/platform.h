/* Small operating-system helpers shared by the solver's outputs, the stream, the renderer and the tools. */
#ifndef SURGE_PLATFORM_H
#define SURGE_PLATFORM_H

#include <stddef.h>

/* Seconds on a monotonic clock (for rates and cadences, not dates). */
double surge_wall_clock_s(void);

/* Creates path and its missing parents (mkdir -p). Returns 0, or -1 with err naming the folder that could not be
 * created or the path that is not a folder; what names the folder in the message ("output", "frames"). */
int surge_make_folders(const char *path, const char *what, char *err, size_t err_len);

#endif
