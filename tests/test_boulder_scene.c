/* The debris surge's boulders as data, without a simulation (surge/boulder_scene.h):
 *   grading    sizes drawn from the built-in curve stay in bounds and follow the truncated curve (Kolmogorov-Smirnov
 *              distance below its 5 % critical value at a fixed seed); bad curve files are refused with file:line
 *   placement  graded discs never overlap, stay inside the block with the gap, lie log-normally behind the front,
 *              repeat with their seed; an impossible request is refused
 *   csv        the disc list reads back exactly; bad lists are refused with file:line
 *   flow       eq. 21 (flow.csv) on a synthetic surge with known answers: a block 1.3 m high moving 2 m/s against
 *              the belt, a disc riding 2 m behind its front and one gone round the period ahead of it (counted as
 *              ahead of the front, the film riding it not counted as surge), fluid splashed next to the wall left
 *              out */
#define _DEFAULT_SOURCE /* erand48 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "surge/boulder_scene.h"
#include "surge/flow_metrics.h"

static int failures = 0;

static void check(const char *name, int ok, const char *detail)
{
    printf("%s: %s%s%s\n", name, ok ? "ok" : "FAILED", detail[0] ? " -- " : "", detail);
    failures += !ok;
}

static int compare_doubles(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

static void group_grading(const char *work)
{
    char err[512], detail[512];
    surge_grading *g = surge_grading_load(NULL, err, sizeof err);
    if (!g) {
        check("grading: the built-in curve loads", 0, err);
        return;
    }
    enum { N = 20000 };
    const double d_min = 0.2, d_max = 1.3;
    static double d[N];
    unsigned short rng[3] = {1, 2, 3};
    int outside = 0;
    for (int i = 0; i < N; i++) {
        d[i] = surge_grading_inverse(g, d_min, d_max, erand48(rng));
        outside += !(d[i] >= d_min && d[i] <= d_max);
    }
    qsort(d, N, sizeof d[0], compare_doubles);
    const double p_min = surge_grading_passing(g, d_min), p_max = surge_grading_passing(g, d_max);
    double ks = 0, mean_d2 = 0;
    for (int i = 0; i < N; i++) {
        const double f = (surge_grading_passing(g, d[i]) - p_min) / (p_max - p_min);
        ks = fmax(ks, fmax(fabs(f - (double)i / N), fabs(f - (double)(i + 1) / N)));
        mean_d2 += d[i] * d[i] / N;
    }
    snprintf(detail, sizeof detail, "%d outside [%g, %g] m; KS distance %.4f (5 %% critical %.4f); rms diameter %.3f m",
             outside, d_min, d_max, ks, 1.36 / sqrt(N), sqrt(mean_d2));
    check("grading: sizes in bounds and distributed as the truncated curve", outside == 0 && ks < 1.36 / sqrt(N),
          detail);
    surge_grading_free(g);

    static const struct {
        const char *text, *words;
    } bad[] = {
        {"size,passing\n0.1,0.5\n", ":1: the header"},
        {"diameter_m,fraction_passing\n0.1,0.5\n0.05,0.6\n", ":3: diameter 0.05"},
        {"diameter_m,fraction_passing\n0.1,0.5\n0.2,0.4\n", ":3: fraction passing 0.4"},
        {"diameter_m,fraction_passing\n0.1,1.5\n", ":2: fraction passing 1.5"},
        {"diameter_m,fraction_passing\n0.1,x\n", ":2: expected"},
        {"diameter_m,fraction_passing\n0.1,0.5,7\n", ":2: expected"},
        {"diameter_m,fraction_passing\n# one point\n0.1,0.5\n", "at least two points"},
    };
    char path[4096];
    snprintf(path, sizeof path, "%s/grading_bad.csv", work);
    int wrong = 0;
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        write_text(path, bad[k].text);
        surge_grading *b = surge_grading_load(path, err, sizeof err);
        if (b || !strstr(err, bad[k].words)) {
            snprintf(detail, sizeof detail, "case %zu: %s", k, b ? "accepted" : err);
            wrong++;
        }
        surge_grading_free(b);
    }
    check("grading: malformed curves are refused naming the line", wrong == 0, wrong ? detail : "");
    surge_grading *missing = surge_grading_load("/nonexistent/grading.csv", err, sizeof err);
    check("grading: a missing file is named", !missing && strstr(err, "/nonexistent/grading.csv"), err);
}

static surge_params surge_scene(int count, int seed)
{
    surge_params p = surge_default_params();
    p.domain.length_m = 33;
    p.domain.height_m = 4;
    p.domain.periodic_x = true;
    p.fluid.x0_m = 1.5;
    p.fluid.x1_m = 21.5;
    p.fluid.depth_m = 1.4;
    p.numerics.dp_m = 0.05;
    p.boulders.placement = SURGE_BOULDERS_GRADED;
    p.boulders.count = count;
    p.boulders.seed = seed;
    return p;
}

static void group_placement(void)
{
    char err[512], detail[512];
    enum { SEEDS = 100, COUNT = 5 }; /* few small discs: the law itself, not the crowding of many near the front */
    static double behind[SEEDS * COUNT];
    int total = 0, overlaps = 0, outside = 0;
    for (int seed = 1; seed <= SEEDS; seed++) {
        surge_params p = surge_scene(COUNT, seed);
        p.boulders.diameter_max_m = 0.4;
        surge_disc *d = NULL;
        const int n = surge_boulders_generate(&p, &d, err, sizeof err);
        if (n != COUNT) {
            check("placement: 5 discs placed", 0, n < 0 ? err : "a wrong count");
            free(d);
            return;
        }
        const double gap = p.numerics.dp_m;
        for (int i = 0; i < n; i++) {
            outside += d[i].x_m < p.fluid.x0_m + d[i].r_m + gap - 1e-12 || d[i].x_m > p.fluid.x1_m - d[i].r_m - gap + 1e-12 ||
                       d[i].y_m < d[i].r_m + gap - 1e-12 || d[i].y_m > p.fluid.depth_m - d[i].r_m - gap + 1e-12;
            for (int j = 0; j < i; j++)
                overlaps += hypot(d[i].x_m - d[j].x_m, d[i].y_m - d[j].y_m) < d[i].r_m + d[j].r_m + gap - 1e-12;
            behind[total++] = p.fluid.x1_m - d[i].x_m;
        }
        free(d);
    }
    qsort(behind, (size_t)total, sizeof behind[0], compare_doubles);
    const double median = behind[total / 2], median_log = log(median / 3.0);
    double spread = 0; /* the log distances' standard deviation, against front_sigma 0.8 */
    double mean_log = 0;
    for (int i = 0; i < total; i++)
        mean_log += log(behind[i]) / total;
    for (int i = 0; i < total; i++)
        spread += (log(behind[i]) - mean_log) * (log(behind[i]) - mean_log) / (total - 1);
    spread = sqrt(spread);
    snprintf(detail, sizeof detail, "%d discs over %d seeds: %d overlaps, %d outside; median distance behind the front "
             "%.2f m (front_median_m 3), sigma of its log %.2f (0.8)", total, SEEDS, overlaps, outside, median,
             spread);
    check("placement: no overlaps, inside the block with the gap", overlaps == 0 && outside == 0, detail);
    check("placement: centres log-normal behind the front (median within 10 %, sigma within 0.1)",
          fabs(median_log) < log(1.1) && fabs(spread - 0.8) < 0.1, detail);

    surge_params p = surge_scene(50, 7);
    surge_disc *a = NULL, *b = NULL, *c = NULL;
    const int na = surge_boulders_generate(&p, &a, err, sizeof err);
    const int nb = surge_boulders_generate(&p, &b, err, sizeof err);
    p.boulders.seed = 8;
    const int nc = surge_boulders_generate(&p, &c, err, sizeof err);
    check("placement: the same seed gives the same discs, another seed others",
          na == 50 && nb == 50 && nc == 50 && !memcmp(a, b, 50 * sizeof *a) && memcmp(a, c, 50 * sizeof *a) != 0, "");
    free(a), free(b), free(c);

    surge_disc *none = NULL;
    p = surge_scene(154, 1);
    const int impossible = surge_boulders_generate(&p, &none, err, sizeof err);
    check("placement: 154 discs in a 20 m block are refused with what was placed", impossible < 0 && !none &&
          strstr(err, "placed") && strstr(err, "of 154 discs"), err);
    p = surge_scene(10, 1);
    p.boulders.diameter_max_m = 1.4;
    const int too_big = surge_boulders_generate(&p, &none, err, sizeof err);
    check("placement: a largest diameter that does not fit the depth is refused", too_big < 0 &&
          strstr(err, "does not fit the fluid depth"), err);
    p = surge_scene(10, 1);
    p.numerics.dp_m = 0.1;
    const int coarse = surge_boulders_generate(&p, &none, err, sizeof err);
    check("placement: discs under 3 dp across are refused, naming the dp that resolves them", coarse < 0 &&
          strstr(err, "at least 3 dp") && strstr(err, "numerics.dp_m <= 0.0666667 m"), err);
}

static void group_csv(const char *work)
{
    char err[512], detail[512], path[4096];
    surge_params p = surge_scene(50, 3);
    surge_disc *d = NULL, *back = NULL;
    const int n = surge_boulders_generate(&p, &d, err, sizeof err);
    if (n > 0) {
        d[0].vx_mps = 0.1 / 3.0, d[1].omega_radps = -1e-300; /* values that need all 17 digits */
    }
    snprintf(path, sizeof path, "%s/discs.csv", work);
    const int written = n > 0 ? surge_discs_write_csv(path, d, n, err, sizeof err) : -1;
    const int m = written == 0 ? surge_discs_read_csv(path, &back, err, sizeof err) : -1;
    check("csv: the disc list reads back bit for bit", m == n && n > 0 && !memcmp(d, back, (size_t)n * sizeof *d),
          m < 0 ? err : "");
    free(d), free(back);

    static const struct {
        const char *text, *words;
    } bad[] = {
        {"x,y,r\n1,1,0.2\n", ":1: the header"},
        {"x_m,y_m,r_m\n1,1,0.2\n1,1\n", ":3: expected 3 numbers"},
        {"x_m,y_m,r_m\n1,1,-0.2\n", ":2: radius -0.2"},
        {"x_m,y_m,r_m\n1,1,nan\n", ":2: expected"},
        {"x_m,y_m,r_m,vx_mps,vy_mps,omega_radps\n1,1,0.2\n", ":2: expected 6 numbers"},
        {"x_m,y_m,r_m\n# nothing\n", "holds no disc"},
    };
    int wrong = 0;
    snprintf(path, sizeof path, "%s/discs_bad.csv", work);
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        write_text(path, bad[k].text);
        surge_disc *r = NULL;
        if (surge_discs_read_csv(path, &r, err, sizeof err) >= 0 || !strstr(err, bad[k].words)) {
            snprintf(detail, sizeof detail, "case %zu: %s", k, r ? "accepted" : err);
            wrong++;
        }
        free(r);
    }
    check("csv: malformed disc lists are refused naming the line", wrong == 0, wrong ? detail : "");
}

static void group_flow(void)
{
    surge_params p = surge_scene(0, 1);
    p.walls.upstream_x_m = 1.5;
    p.numerics.dp_m = 0.1;
    p.fluid.viscosity_m2ps = 0.28;
    p.body.slope_deg = 10.1;
    surge_snapshot s = {0};
    surge_snapshot_reserve(&s, 200 * 13 + 330 + 1 + 3);
    int n = 0;
    for (int i = 0; i < 200; i++) /* the block: 20 m from the wall's face, 13 rows */
        for (int j = 0; j < 13; j++, n++) {
            s.x_m[n] = 1.5 + (i + 0.5) * 0.1, s.y_m[n] = (j + 0.5) * 0.1;
            s.vx_mps[n] = -3.5f + 2.0f, s.vy_mps[n] = 0, s.kind[n] = SURGE_KIND_FLUID;
        }
    s.x_m[n] = 3.0, s.y_m[n] = 3.0, s.vx_mps[n] = 50, s.kind[n++] = SURGE_KIND_FLUID; /* within 5 m: left out */
    for (int i = 0; i < 3; i++, n++) /* a film riding the disc that left (below): not the surge */
        s.x_m[n] = 1.5 + 30 - 33 + 0.1 * (i - 1), s.y_m[n] = 0.6, s.vx_mps[n] = -0.5f, s.vy_mps[n] = 0,
        s.kind[n] = SURGE_KIND_FLUID;
    for (int i = 0; i < 330; i++, n++) /* the belt */
        s.x_m[n] = (i + 0.5) * 0.1, s.y_m[n] = -0.05, s.vx_mps[n] = -3.5f, s.vy_mps[n] = 0,
        s.kind[n] = SURGE_KIND_MOVING_WALL;
    s.count = n;
    surge_snapshot_reserve_boulders(&s, 2);
    s.boulders.count = 2;
    s.boulders.x_m[0] = 1.5 + 18, s.boulders.y_m[0] = 1.2, s.boulders.radius_m[0] = 0.3;
    /* one that left the surge, rolled down the belt and went round the period: behind the wall, 30 m from it */
    s.boulders.x_m[1] = 1.5 + 30 - 33, s.boulders.y_m[1] = 0.3, s.boulders.radius_m[1] = 0.25;
    surge_flow_metrics m;
    const int rc = surge_flow_metrics_compute(&s, &p, &m);
    const double g = 9.81, slope = 10.1 * 3.14159265358979323846 / 180;
    const double fr = 2.0 / sqrt(g * 1.3), mu = g * sin(slope) * 1.3 * 1.3 / (3 * 2.0 * 0.28);
    char detail[512];
    snprintf(detail, sizeof detail, "h_max %.6g (1.3), with boulders %.6g (1.5), u_bar %.6g (2), Fr %.6g (%.6g), "
             "mu_eq/mu0 %.6g (%.6g), front %.6g m (20), boulders %.6g m behind on average (2 and -10: -4), %d ahead "
             "of the front (1), %d fluid (1950: the block past 5 m)", m.h_max_m,
             m.h_max_with_boulders_m, m.u_bar_mps, m.froude, fr, m.mu_eq_over_mu0, mu, m.front_from_wall_m,
             m.boulders_behind_front_m, m.boulders_ahead_of_front, m.fluid_counted);
    check("flow: eq. 21 on a synthetic surge gives the known numbers", rc == 0 && fabs(m.h_max_m - 1.3) < 1e-9 &&
          fabs(m.h_max_with_boulders_m - 1.5) < 1e-9 && fabs(m.u_bar_mps - 2) < 1e-6 && fabs(m.froude - fr) < 1e-6 &&
          fabs(m.mu_eq_over_mu0 - mu) < 1e-6 && fabs(m.front_from_wall_m - 20) < 1e-9 &&
          fabs(m.boulders_behind_front_m + 4) < 1e-9 && m.boulders_ahead_of_front == 1 && m.fluid_counted == 1950,
          detail);
    surge_snapshot_free(&s);
}

int main(int argc, char **argv)
{
    if (argc != 3)
        return 2;
    if (!strcmp(argv[1], "grading"))
        group_grading(argv[2]);
    else if (!strcmp(argv[1], "placement"))
        group_placement();
    else if (!strcmp(argv[1], "csv"))
        group_csv(argv[2]);
    else if (!strcmp(argv[1], "flow"))
        group_flow();
    else
        return 2;
    return failures ? 1 : 0;
}
