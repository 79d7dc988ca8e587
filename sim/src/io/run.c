#define _POSIX_C_SOURCE 200809L
#include "surge/platform.h"
#include "surge/run.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "surge/boulder_scene.h"
#include "surge/flow_metrics.h"
#include "surge/vtk_output.h"

typedef struct run_outputs {
    const char *dir;
    surge_pvd *pvd;
    surge_pvd *boulder_pvd; /* boulders.pvd, when the scene has boulders */
    FILE *csv;
    FILE *flow_csv;         /* flow.csv, when output.flow_interval_s > 0 */
    surge_contact_impulses flow_impulses; /* the discs' contact impulses at flow.csv's last row (or the run's start) */
    double flow_time_s;                   /* and that row's time */
    surge_snapshot snap;
    int64_t last_snapshot_step; /* the step of the last snapshot in the collection */
    int64_t last_checkpoint_step;  /* the step of the checkpoint on disk (-1: none written by this run) */
    surge_params checkpoint_params; /* the parameters it holds */
} run_outputs;

surge_run_options surge_default_run_options(void)
{
    surge_run_options o;
    memset(&o, 0, sizeof o);
    o.output_dir = "out";
    o.threads = 1;
    return o;
}

static void join(char *out, size_t len, const char *dir, const char *name) { snprintf(out, len, "%s/%s", dir, name); }

static int write_params(const surge_sim *sim, const run_outputs *o, int threads, char *err, size_t err_len)
{
    char path[4096];
    join(path, sizeof path, o->dir, "params.ini");
    FILE *f = fopen(path, "w");
    if (!f) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    const surge_derived *d = surge_sim_derived(sim);
    char machine[512];
    surge_machine_description(machine, sizeof machine);
    fprintf(f, "# surge: full resolved parameter set of this run (reloads as a case file)\n"
               "# program: %s\n"
               "# machine: %s\n"
               "# derived: h_m = %.9g, c0_mps = %.9g (expected speed %.6g m/s), particle_mass_kgpm = %.9g\n"
               "# derived: fluid particles = %d, wall particles = %d, threads = %d\n\n",
            surge_build_description(), machine, d->h_m, d->c0_mps, d->expected_speed_mps, d->particle_mass_kg, d->fluid_count, d->wall_count, threads);
    surge_params_write(surge_sim_params(sim), f);
    if (fclose(f) != 0) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}

static int write_snapshot(const surge_sim *sim, run_outputs *o, const char *name, int add_to_collection,
                          char *err, size_t err_len)
{
    char file[64], path[4096];
    if (name)
        snprintf(file, sizeof file, "%s", name);
    else
        surge_run_snapshot_name(surge_sim_step_count(sim), file, sizeof file);
    join(path, sizeof path, o->dir, file);
    if (surge_sim_snapshot(sim, &o->snap) != 0) {
        snprintf(err, err_len, "out of memory taking a snapshot");
        return -1;
    }
    if (surge_vtp_write(path, &o->snap, err, err_len) != 0)
        return -1;
    if (add_to_collection && surge_pvd_add(o->pvd, surge_sim_time(sim), file, err, err_len) != 0)
        return -1;
    if (o->boulder_pvd) { /* boulders_<same suffix> next to the particles' file */
        char boulder_file[80];
        snprintf(boulder_file, sizeof boulder_file, "boulders_%s", strncmp(file, "snap_", 5) ? file : file + 5);
        join(path, sizeof path, o->dir, boulder_file);
        if (surge_vtp_write_boulders(path, &o->snap, err, err_len) != 0)
            return -1;
        if (add_to_collection && surge_pvd_add(o->boulder_pvd, surge_sim_time(sim), boulder_file, err, err_len) != 0)
            return -1;
    }
    if (add_to_collection)
        o->last_snapshot_step = surge_sim_step_count(sim);
    return 0;
}

void surge_run_snapshot_name(int64_t step, char *name, size_t len)
{
    snprintf(name, len, "snap_%09lld.vtp", (long long)step);
}

static int write_diagnostics(const surge_sim *sim, run_outputs *o, char *err, size_t err_len)
{
    surge_diagnostics d = surge_sim_diagnostics(sim);
    /* flushed row by row: a run that dies still leaves its time series */
    if (fprintf(o->csv, "%.9g,%lld,%.6g,%.9g,%.6g,%.6g,%.9g,%.6g,%.6g", d.time_s, (long long)d.step, d.dt_s,
                d.kinetic_energy_jpm, d.max_speed_mps, d.max_density_deviation, d.fluid_volume_m2, d.mean_vx_mps,
                d.bottom_wall_speed_mps) < 0 ||
        (surge_sim_reports_solves(sim) &&
         fprintf(o->csv, ",%d,%.3g,%d,%.3g", d.pressure_iterations, d.pressure_residual, d.viscous_iterations,
                 d.viscous_residual) < 0) ||
        fputc('\n', o->csv) == EOF || fflush(o->csv) != 0) {
        snprintf(err, err_len, "cannot write %s/diagnostics.csv: %s", o->dir, strerror(errno));
        return -1;
    }
    return 0;
}

/* A row of flow.csv (surge/flow_metrics.h); a snapshot without fluid past the ignored zone gives NaN numbers. */
static int write_flow(const surge_sim *sim, run_outputs *o, char *err, size_t err_len)
{
    if (surge_sim_snapshot(sim, &o->snap) != 0) {
        snprintf(err, err_len, "out of memory taking a snapshot");
        return -1;
    }
    surge_flow_metrics m;
    surge_flow_metrics_compute(&o->snap, surge_sim_params(sim), &m);
    /* the mean contact forces on the discs since the last row (NaN in a run's first row) */
    const surge_contact_impulses now = surge_sim_contact_impulses(sim), *then = &o->flow_impulses;
    const double span_s = surge_sim_time(sim) - o->flow_time_s;
    const double per_s = span_s > 0 ? 1.0 / span_s : NAN;
    if (fprintf(o->flow_csv, "%.9g,%lld,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n",
                m.time_s, (long long)surge_sim_step_count(sim), m.h_max_m, m.h_max_with_boulders_m, m.u_bar_mps,
                m.froude, m.mu_eq_over_mu0, m.front_from_wall_m, m.boulders_behind_front_m, m.fluid_counted,
                m.boulders_ahead_of_front, (now.bed_normal_nspm - then->bed_normal_nspm) * per_s,
                (now.bed_friction_nspm - then->bed_friction_nspm) * per_s,
                (now.wall_normal_nspm - then->wall_normal_nspm) * per_s,
                (now.wall_friction_nspm - then->wall_friction_nspm) * per_s,
                (now.disc_normal_nspm - then->disc_normal_nspm) * per_s,
                (now.disc_friction_nspm - then->disc_friction_nspm) * per_s) < 0 ||
        fflush(o->flow_csv) != 0) {
        snprintf(err, err_len, "cannot write %s/flow.csv: %s", o->dir, strerror(errno));
        return -1;
    }
    o->flow_impulses = now;
    o->flow_time_s = surge_sim_time(sim);
    return 0;
}

/* name: checkpoint.bin, or last_good.bin for the last good state of a run the health monitor stopped (which keeps
 * the periodic checkpoint.bin, an earlier state to rerun the approach from with other settings) */
static int write_checkpoint(const surge_sim *sim, run_outputs *o, const char *name, char *err, size_t err_len)
{
    char path[4096];
    join(path, sizeof path, o->dir, name);
    if (surge_sim_checkpoint_write(sim, path, err, err_len) != 0)
        return -1;
    o->last_checkpoint_step = surge_sim_step_count(sim);
    o->checkpoint_params = *surge_sim_params(sim);
    return 0;
}

/* The first multiple of interval strictly after t. */
static double next_time(double t, double interval)
{
    return interval > 0 ? (floor(t / interval + 1e-9) + 1.0) * interval : INFINITY;
}

/* A diagnostics.csv line to keep on restart: the header, or a row whose step (second column) is at or before the
 * checkpoint's; the rows after it belong to the interrupted run's lost continuation. */
static int row_at_or_before_step(const char *line, void *checkpoint_step)
{
    const char *comma = strchr(line, ',');
    char *end = NULL;
    const long long step = comma ? strtoll(comma + 1, &end, 10) : 0;
    return !comma || end == comma + 1 || step <= *(const long long *)checkpoint_step;
}

/* A time series (diagnostics.csv, flow.csv) opened for this run: on a restart the rows up to the checkpoint's step
 * are kept and new rows appended (a file with other columns is refused); a new file gets the header. NULL with err. */
static FILE *open_series(const run_outputs *o, const char *name, const char *header, const surge_sim *sim,
                         int restarted, char *err, size_t err_len)
{
    char path[4096];
    join(path, sizeof path, o->dir, name);
    long long checkpoint_step = (long long)surge_sim_step_count(sim);
    if (restarted) { /* rows of other columns (an earlier version's file) are not appended to */
        FILE *old = fopen(path, "r");
        char *first = NULL;
        size_t capacity = 0;
        int other = 0;
        if (old && getline(&first, &capacity, old) > 0) {
            first[strcspn(first, "\r\n")] = '\0';
            other = first[0] != '\0' && strcmp(first, header) != 0;
        }
        if (other)
            snprintf(err, err_len, "'%s' has the columns '%.200s', not this version's '%.200s': restart into another "
                     "folder (-o), or move the file away", path, first, header);
        free(first);
        if (old)
            fclose(old);
        if (other)
            return NULL;
    }
    if (restarted && surge_file_keep_lines(path, row_at_or_before_step, &checkpoint_step, err, err_len) != 0)
        return NULL;
    FILE *f = fopen(path, restarted ? "a" : "w");
    if (!f) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return NULL;
    }
    const int empty = fseek(f, 0, SEEK_END) == 0 && ftell(f) == 0; /* a restart into a new folder */
    if (empty && fprintf(f, "%s\n", header) < 0) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        fclose(f);
        return NULL;
    }
    return f;
}

/* When an output is next due. The interval is a live parameter: a change (from the control socket) re-schedules
 * it from the current time, so that setting an interval that was 0 takes effect. */
typedef struct {
    double interval_s; /* the interval next_s was scheduled with */
    double next_s;
} output_schedule;

static output_schedule schedule_from(double t, double interval_s)
{
    return (output_schedule){interval_s, next_time(t, interval_s)};
}

/* Whether the output is due at time t (interval 0: at every step if every_step_when_zero, else never). */
static int output_due(output_schedule *s, double t, double interval_s, int every_step_when_zero)
{
    if (interval_s != s->interval_s)
        *s = schedule_from(t, interval_s);
    if (interval_s == 0)
        return every_step_when_zero;
    if (t < s->next_s)
        return 0;
    s->next_s = next_time(t, interval_s);
    return 1;
}

/* held_s: wall time the run was held at a step boundary (paused by a control client), left out of the rates */
static void print_progress(const surge_sim *sim, double start_wall, double held_s, int64_t start_step,
                           double start_time)
{
    const double elapsed = surge_wall_clock_s() - start_wall - held_s, t = surge_sim_time(sim);
    const double end = surge_sim_params(sim)->time.end_s;
    const double steps = (double)(surge_sim_step_count(sim) - start_step);
    const double rate = elapsed > 0 ? steps / elapsed : 0;
    /* the last step may end past end_s (a step is not cut to land on it): then nothing is left */
    const double eta = t > start_time ? elapsed * fmax(0.0, end - t) / (t - start_time) : 0;
    const int64_t halvings = surge_sim_diagnostics(sim).step_halvings;
    char halved[48] = "";
    if (halvings > 0)
        snprintf(halved, sizeof halved, "  steps halved %lld times", (long long)halvings);
    fprintf(stderr, "t = %.4f / %.4g s  step %lld  dt %.3g s  %.4g steps/s  %.3g particle-steps/s  ETA %02d:%02d:%02d%s\n",
            t, end, (long long)surge_sim_step_count(sim), surge_sim_last_dt(sim), rate,
            rate * surge_sim_derived(sim)->fluid_count, (int)(eta / 3600), (int)fmod(eta / 60, 60), (int)fmod(eta, 60),
            halved);
}

/* The step-boundary callback; time spent in calls that hold the run (paused) is added to held_s. */
static int call_boundary(const surge_run_options *opt, surge_sim *sim, double *held_s)
{
    if (!opt->at_step_boundary)
        return SURGE_CONTINUE;
    const double from = surge_wall_clock_s();
    const int requests = opt->at_step_boundary(sim, opt->user);
    if (requests & SURGE_REQUEST_AGAIN)
        *held_s += surge_wall_clock_s() - from;
    return requests;
}

/* boulders.csv: the discs at the start, which a case reloads with boulders.placement = file (surge/boulder_scene.h) */
static int write_initial_discs(const surge_sim *sim, const run_outputs *o, char *err, size_t err_len)
{
    surge_snapshot snap = {0};
    if (surge_sim_snapshot(sim, &snap) != 0) {
        snprintf(err, err_len, "out of memory");
        return -1;
    }
    const surge_boulder_state *b = &snap.boulders;
    surge_disc *discs = malloc(sizeof *discs * (size_t)(b->count > 0 ? b->count : 1));
    int rc = -1;
    if (discs) {
        for (int i = 0; i < b->count; i++)
            discs[i] = (surge_disc){b->x_m[i], b->y_m[i], b->radius_m[i], b->vx_mps[i], b->vy_mps[i], b->omega_radps[i]};
        char path[4096];
        join(path, sizeof path, o->dir, "boulders.csv");
        rc = surge_discs_write_csv(path, discs, b->count, err, err_len);
    } else {
        snprintf(err, err_len, "out of memory");
    }
    free(discs);
    surge_snapshot_free(&snap);
    return rc;
}

/* The run's files: params.ini, run.pvd (boulders.pvd), diagnostics.csv (flow.csv), and for a new run the initial
 * rows and snapshot; -1 with err set (what was opened is closed by the caller) */
static int open_outputs(surge_sim *sim, const surge_run_options *opt, run_outputs *o, char *err, size_t err_len)
{
    char path[4096];
    if (surge_make_folders(opt->output_dir, "the output", err, err_len) != 0 ||
        write_params(sim, o, opt->threads, err, err_len) != 0)
        return -1;
    /* a restart keeps the earlier run's entries up to and including its final snapshot (this state) */
    const double keep_until_s = opt->restarted ? nextafter(surge_sim_time(sim), INFINITY) : -1.0;
    join(path, sizeof path, o->dir, "run.pvd");
    if (!(o->pvd = surge_pvd_open(path, keep_until_s, err, err_len)))
        return -1;
    if (surge_sim_derived(sim)->boulder_count > 0) {
        join(path, sizeof path, o->dir, "boulders.pvd");
        if (!(o->boulder_pvd = surge_pvd_open(path, keep_until_s, err, err_len)))
            return -1;
    }
    const surge_params *p = surge_sim_params(sim);
    o->csv = open_series(o, "diagnostics.csv", surge_sim_reports_solves(sim)
                         ? "time_s,step,dt_s,kinetic_energy_jpm,max_speed_mps,max_density_deviation,fluid_volume_m2,"
                           "mean_vx_mps,bottom_wall_speed_mps,pressure_iterations,pressure_residual,"
                           "viscous_iterations,viscous_residual"
                         : "time_s,step,dt_s,kinetic_energy_jpm,max_speed_mps,max_density_deviation,fluid_volume_m2,"
                           "mean_vx_mps,bottom_wall_speed_mps", sim, opt->restarted, err, err_len);
    if (!o->csv)
        return -1;
    if (p->output.flow_interval_s > 0 &&
        !(o->flow_csv = open_series(o, "flow.csv", "time_s,step,h_max_m,h_max_with_boulders_m,u_bar_mps,froude,"
                                    "mu_eq_over_mu0,front_from_wall_m,boulders_behind_front_m,fluid_counted,"
                                    "boulders_ahead_of_front,bed_normal_force_npm,bed_friction_force_npm,"
                                    "wall_normal_force_npm,wall_friction_force_npm,disc_normal_force_npm,"
                                    "disc_friction_force_npm", sim, opt->restarted, err, err_len)))
        return -1;
    o->flow_impulses = surge_sim_contact_impulses(sim);
    o->flow_time_s = surge_sim_time(sim);
    if (!opt->restarted &&
        (write_diagnostics(sim, o, err, err_len) != 0 || write_snapshot(sim, o, NULL, 1, err, err_len) != 0 ||
         (o->flow_csv && write_flow(sim, o, err, err_len) != 0) ||
         (surge_sim_derived(sim)->boulder_count > 0 && write_initial_discs(sim, o, err, err_len) != 0)))
        return -1;
    return 0;
}

/* Where a run's loop stands: the outputs' schedules and the progress line's clock */
typedef struct run_clock {
    output_schedule snapshots, diagnostics, checkpoints, flows;
    double start_wall, start_time, next_progress, held_s;
    int64_t start_step;
} run_clock;

/* The outputs due after a step; -1 with err set when one cannot be written (*fatal: skip the final outputs too) */
static int write_due_outputs(surge_sim *sim, run_outputs *o, run_clock *c, int *fatal, char *err, size_t err_len)
{
    const surge_params *p = surge_sim_params(sim); /* live values may change between steps */
    const double t = surge_sim_time(sim);
    *fatal = 0;
    if (output_due(&c->diagnostics, t, p->output.diagnostics_interval_s, 1) &&
        write_diagnostics(sim, o, err, err_len) != 0)
        return -1; /* the final snapshot and checkpoint are still tried */
    *fatal = 1;
    if (output_due(&c->snapshots, t, p->output.snapshot_interval_s, 0) && write_snapshot(sim, o, NULL, 1, err, err_len) != 0)
        return -1;
    if (o->flow_csv && output_due(&c->flows, t, p->output.flow_interval_s, 0) && write_flow(sim, o, err, err_len) != 0)
        return -1;
    if (output_due(&c->checkpoints, t, p->output.checkpoint_interval_s, 0) &&
        write_checkpoint(sim, o, "checkpoint.bin", err, err_len) != 0)
        return -1;
    *fatal = 0;
    if (p->output.progress_interval_s > 0 && surge_wall_clock_s() >= c->next_progress) {
        print_progress(sim, c->start_wall, c->held_s, c->start_step, c->start_time);
        c->next_progress = surge_wall_clock_s() + p->output.progress_interval_s;
    }
    return 0;
}

/* Steps to the end time, a stop or a failure, serving the step-boundary callback's requests; *fatal: an output failed
 * and the final outputs are skipped */
static surge_run_result step_until_done(surge_sim *sim, const surge_run_options *opt, run_outputs *o, run_clock *c,
                                        int *fatal, char *err, size_t err_len)
{
    const surge_params *p = surge_sim_params(sim);
    *fatal = 1;
    int requests = call_boundary(opt, sim, &c->held_s);
    for (;;) {
        /* a change made at the step of the checkpoint on disk goes into it: the journal lists the change at this
         * step, and a restart from this checkpoint keeps the journal up to it */
        if (surge_sim_step_count(sim) == o->last_checkpoint_step &&
            surge_params_live_differ(&o->checkpoint_params, surge_sim_params(sim)))
            requests |= SURGE_REQUEST_CHECKPOINT;
        if (requests & SURGE_REQUEST_SNAPSHOT && surge_sim_step_count(sim) != o->last_snapshot_step &&
            write_snapshot(sim, o, NULL, 1, err, err_len) != 0)
            return SURGE_RUN_IO_ERROR;
        if (requests & SURGE_REQUEST_CHECKPOINT && write_checkpoint(sim, o, "checkpoint.bin", err, err_len) != 0)
            return SURGE_RUN_IO_ERROR;
        *fatal = 0;
        if (requests & SURGE_REQUEST_STOP)
            return SURGE_RUN_STOPPED;
        if (requests & SURGE_REQUEST_AGAIN) {
            requests = call_boundary(opt, sim, &c->held_s);
            *fatal = 1;
            continue;
        }
        if (surge_sim_time(sim) >= p->time.end_s)
            return SURGE_RUN_FINISHED;
        if (opt->stop && *opt->stop)
            return SURGE_RUN_INTERRUPTED;
        if (surge_sim_step(sim) != 0) {
            snprintf(err, err_len, "%s", surge_sim_health(sim)->message);
            return SURGE_RUN_UNHEALTHY;
        }
        if (write_due_outputs(sim, o, c, fatal, err, err_len) != 0)
            return SURGE_RUN_IO_ERROR;
        requests = call_boundary(opt, sim, &c->held_s);
        *fatal = 1;
    }
}

/* The final state always reaches disk: a snapshot and a checkpoint (after a health failure the last good state, as
 * last_good.vtp and last_good.bin) */
static surge_run_result write_final(surge_sim *sim, run_outputs *o, surge_run_result result, char *err, size_t err_len)
{
    char final_err[512];
    const int unhealthy = result == SURGE_RUN_UNHEALTHY;
    const char *final_name = unhealthy ? "last_good.vtp" : NULL;
    const int snapshot_due = result == SURGE_RUN_UNHEALTHY || surge_sim_step_count(sim) != o->last_snapshot_step;
    if ((snapshot_due &&
         write_snapshot(sim, o, final_name, result != SURGE_RUN_UNHEALTHY, final_err, sizeof final_err) != 0) ||
        write_checkpoint(sim, o, unhealthy ? "last_good.bin" : "checkpoint.bin", final_err, sizeof final_err) != 0) {
        if (result != SURGE_RUN_UNHEALTHY && result != SURGE_RUN_IO_ERROR) /* the first error is the one to name */
            snprintf(err, err_len, "%s", final_err);
        result = result == SURGE_RUN_UNHEALTHY ? result : SURGE_RUN_IO_ERROR;
    }
    return result;
}

/* Closes the run's files; a diagnostics or flow table that cannot be completed is an output error */
static surge_run_result close_outputs(run_outputs *o, surge_run_result result, char *err, size_t err_len)
{
    if (o->csv && fclose(o->csv) != 0 && result != SURGE_RUN_UNHEALTHY && result != SURGE_RUN_IO_ERROR) {
        snprintf(err, err_len, "cannot write diagnostics.csv: %s", strerror(errno));
        result = SURGE_RUN_IO_ERROR;
    }
    if (o->flow_csv && fclose(o->flow_csv) != 0 && result != SURGE_RUN_UNHEALTHY && result != SURGE_RUN_IO_ERROR) {
        snprintf(err, err_len, "cannot write flow.csv: %s", strerror(errno));
        result = SURGE_RUN_IO_ERROR;
    }
    surge_pvd_close(o->pvd);
    surge_pvd_close(o->boulder_pvd);
    surge_snapshot_free(&o->snap);
    return result;
}

surge_run_result surge_run(surge_sim *sim, const surge_run_options *opt, char *err, size_t err_len)
{
    run_outputs o = {.dir = opt->output_dir, .last_snapshot_step = opt->restarted ? surge_sim_step_count(sim) : -1,
                     .last_checkpoint_step = -1};
    if (open_outputs(sim, opt, &o, err, err_len) != 0)
        return close_outputs(&o, SURGE_RUN_IO_ERROR, err, err_len);
    const surge_params *p = surge_sim_params(sim); /* live values may change between steps */
    const double now = surge_sim_time(sim), start_wall = surge_wall_clock_s();
    run_clock clock = {schedule_from(now, p->output.snapshot_interval_s), schedule_from(now, p->output.diagnostics_interval_s),
                       schedule_from(now, p->output.checkpoint_interval_s), schedule_from(now, p->output.flow_interval_s),
                       start_wall, now, start_wall + p->output.progress_interval_s, 0, surge_sim_step_count(sim)};
    int fatal = 0;
    surge_run_result result = step_until_done(sim, opt, &o, &clock, &fatal, err, err_len);
    if (!fatal) {
        result = write_final(sim, &o, result, err, err_len);
        if (p->output.progress_interval_s > 0)
            print_progress(sim, clock.start_wall, clock.held_s, clock.start_step, clock.start_time);
    }
    return close_outputs(&o, result, err, err_len);
}
