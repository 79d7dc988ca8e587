/* What the commands of the surge program share: exit statuses, the parsed command line, the case's parameters,
 * the output folders and the resolution report. */
#ifndef SURGE_APP_CLI_H
#define SURGE_APP_CLI_H

#include <stddef.h>

#include "surge/params.h"
#include "surge/publisher.h"
#include "surge/sim.h"

enum { EXIT_OK = 0, EXIT_UNHEALTHY = 1, EXIT_USAGE = 2, EXIT_IO = 3, EXIT_INTERRUPTED = 4 };
enum { ENDPOINT_BYTES = 256 };

typedef struct cli {
    const char *case_path;
    const char *restart_path;
    const char *output_dir;
    const char *overrides[256];
    int override_count;
    int threads;
    char publish[ENDPOINT_BYTES];
    char control[ENDPOINT_BYTES];
    int publish_remote, control_remote; /* the endpoint can be reached from other machines */
    const char *curve_key_path;         /* --curve-key: the run's secret key file (CURVE on both sockets) */
    const char *curve_clients_path;     /* --curve-clients: the allowed clients' .pub file or folder */
    const char *replay_path;
    surge_publisher_def publisher;
    int paused;
    const char *frames_dir;
    const char *movie_path;
    const char *font_path;
    int overwrite; /* --overwrite: replace an earlier run's files and frames */
    /* the default scene renders into its run folder (surge run without a case): the paths it chose */
    char default_frames_dir[4200], default_movie_path[4200];
} cli;

/* The commands; each takes the arguments after its name and returns the exit status. */
int command_run(int argc, char **argv);
int command_render(int argc, char **argv);
int command_check(int argc, char **argv);
int command_params(int argc, char **argv);
int command_version(int argc, char **argv);
int command_keygen(int argc, char **argv);

/* cli.c: the options */
int wants_help(int argc, char **argv);
/* Fills c from the arguments; the run options (all but -s) only with allow_run_options. 0, or -1 with the message
 * printed. */
int parse_cli(int argc, char **argv, cli *c, int allow_run_options);

/* case_loading.c: the parameters */
int load_case(const cli *c, surge_params *p);
void print_case_error(const cli *c, const char *err);
int fit_frame_height(surge_params *p, const surge_sim *sim, const char *path, char *err, size_t err_len);

/* output_folders.c: where the outputs go, and refusing to write over earlier ones */
void default_output_dir(const char *case_path, char *out, size_t len);
void folder_of(const char *path, char *folder, size_t len);
int same_folder(const char *a, const char *b);
int claim_folder(const char *folder, int (*belongs)(const char *name), int overwrite, const char *what,
                 const char *hint);
int fresh_default_folder(char *folder, size_t len);
int claim_movie(const char *movie_path, int may_replace);

/* resolution_report.c: warnings and cost estimates for a built scene */
void report_resolution(const surge_sim *sim, int verbose);
void warn_diffusive_compressibility(const surge_sim *sim);

#endif
