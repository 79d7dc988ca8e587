/* Boulders as data: the grading curve, the graded placement and the disc list's CSV (see surge/boulder_scene.h). */
#define _DEFAULT_SOURCE /* erand48 */
#include "surge/boulder_scene.h"
#include "boulders/placement.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const double pi = 3.14159265358979323846;
enum { MAX_GRADING_POINTS = 10000, MAX_DISCS = 20000, MAX_PLACEMENT_TRIES = 2000000, LINE_BYTES = 4096 };

struct surge_grading {
    int count;
    double *diameter_m, *passing;
};

/* The built-in stand-in curve (docs/boulders.md): not the paper's (its Fig. 6a is a figure of the Piton et al.
 * 2018 measurement, not a table). 70 % finer than 0.2 m; above that, by number, an exponential tail of scale
 * 0.17 m, P(d) = 0.7 + 0.3 (1 - exp(-(d - 0.2 m) / 0.17 m)), which gives discs of about 0.4 m rms between 0.2 and
 * 1.4 m: 50 of them cover 13 % of the paper's 33 m x 1.4 m flow, as its phi = 0.13 with 50 boulders. */
static const double standin_diameter_m[] = {0.002, 0.02, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.2, 1.4, 2.0};
static const double standin_passing[] = {0.05, 0.2, 0.35, 0.5, 0.7, 0.8334, 0.9075, 0.9486, 0.9715, 0.9912, 0.9973,
                                         0.9992, 0.99974, 1.0};

static surge_grading *grading_new(int count)
{
    surge_grading *g = calloc(1, sizeof *g);
    if (g && (!(g->diameter_m = malloc(sizeof(double) * (size_t)count)) ||
              !(g->passing = malloc(sizeof(double) * (size_t)count)))) {
        surge_grading_free(g);
        return NULL;
    }
    return g;
}

void surge_grading_free(surge_grading *g)
{
    if (!g)
        return;
    free(g->diameter_m);
    free(g->passing);
    free(g);
}

/* The line without its end of line and surrounding blanks; NULL at a comment or blank line. */
static char *trimmed(char *line)
{
    line[strcspn(line, "\r\n")] = '\0';
    while (isspace((unsigned char)*line))
        line++;
    size_t n = strlen(line);
    while (n > 0 && isspace((unsigned char)line[n - 1]))
        line[--n] = '\0';
    return line[0] == '\0' || line[0] == '#' ? NULL : line;
}

/* Splits a CSV row of numbers into at most max values; the count, or -1 with the column that is not a number. */
static int csv_numbers(char *row, double *values, int max, int *bad_column)
{
    int n = 0;
    for (char *field = row;; n++) {
        char *end;
        while (isspace((unsigned char)*field))
            field++;
        if (n == max) {
            *bad_column = n + 1;
            return -1;
        }
        errno = 0;
        values[n] = strtod(field, &end);
        while (isspace((unsigned char)*end))
            end++;
        if (end == field || errno == ERANGE || !isfinite(values[n]) || (*end != ',' && *end != '\0')) {
            *bad_column = n + 1;
            return -1;
        }
        if (*end == '\0')
            return n + 1;
        field = end + 1;
    }
}

/* The header: column names separated by commas (blanks allowed). 1 when it is exactly names[0..count). */
static int header_is(const char *line, const char *const *names, int count)
{
    const char *c = line;
    for (int k = 0; k < count; k++) {
        while (isspace((unsigned char)*c))
            c++;
        const size_t n = strlen(names[k]);
        if (strncmp(c, names[k], n) != 0)
            return 0;
        c += n;
        while (isspace((unsigned char)*c))
            c++;
        if (k + 1 < count && *c++ != ',')
            return 0;
    }
    return *c == '\0';
}

/* Opens a CSV the parameter `what` names; NULL with err set. A pipe or a device (/dev/zero) would be read without
 * end, so only a regular file is read. */
static FILE *open_csv(const char *path, const char *what, char *err, size_t err_len)
{
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        snprintf(err, err_len, "%s: '%s' is not a regular file (a CSV file was expected)", what, path);
        return NULL;
    }
    FILE *f = fopen(path, "r");
    if (!f)
        snprintf(err, err_len, "%s: cannot read '%s': %s", what, path, strerror(errno));
    return f;
}

surge_grading *surge_grading_load(const char *path, char *err, size_t err_len)
{
    if (!path || !path[0]) {
        const int n = (int)(sizeof standin_passing / sizeof standin_passing[0]);
        surge_grading *g = grading_new(n);
        if (!g) {
            snprintf(err, err_len, "out of memory");
            return NULL;
        }
        g->count = n;
        memcpy(g->diameter_m, standin_diameter_m, sizeof standin_diameter_m);
        memcpy(g->passing, standin_passing, sizeof standin_passing);
        return g;
    }
    FILE *f = open_csv(path, "boulders.grading_file", err, err_len);
    if (!f)
        return NULL;
    surge_grading *g = grading_new(MAX_GRADING_POINTS);
    char buffer[LINE_BYTES];
    int line_number = 0, header_seen = 0, ok = g != NULL;
    if (!g)
        snprintf(err, err_len, "out of memory");
    static const char *const names[] = {"diameter_m", "fraction_passing"};
    while (ok && fgets(buffer, sizeof buffer, f)) {
        line_number++;
        char *line = trimmed(buffer);
        if (!line)
            continue;
        if (!header_seen) {
            header_seen = 1;
            if (!header_is(line, names, 2)) {
                snprintf(err, err_len, "%s:%d: the header must be 'diameter_m,fraction_passing', got '%.80s'", path,
                         line_number, line);
                ok = 0;
            }
            continue;
        }
        double v[2];
        int bad = 0;
        const int got = csv_numbers(line, v, 2, &bad);
        const int k = g->count;
        if (got != 2) {
            snprintf(err, err_len, "%s:%d: expected a diameter in m and a fraction passing, got '%.80s'", path,
                     line_number, line);
            ok = 0;
        } else if (k == MAX_GRADING_POINTS) {
            snprintf(err, err_len, "%s:%d: more than %d points", path, line_number, MAX_GRADING_POINTS);
            ok = 0;
        } else if (!(v[0] > 0) || (k > 0 && !(v[0] > g->diameter_m[k - 1]))) {
            snprintf(err, err_len, "%s:%d: diameter %g m must be positive and larger than the row before's", path,
                     line_number, v[0]);
            ok = 0;
        } else if (!(v[1] >= 0 && v[1] <= 1) || (k > 0 && v[1] < g->passing[k - 1])) {
            snprintf(err, err_len, "%s:%d: fraction passing %g must lie in [0, 1] and not fall as the diameter grows",
                     path, line_number, v[1]);
            ok = 0;
        } else {
            g->diameter_m[k] = v[0];
            g->passing[k] = v[1];
            g->count++;
        }
    }
    fclose(f);
    if (ok && g->count < 2) {
        snprintf(err, err_len, "%s: a grading curve needs at least two points (diameter_m,fraction_passing rows)",
                 path);
        ok = 0;
    }
    if (!ok) {
        surge_grading_free(g);
        return NULL;
    }
    return g;
}

double surge_grading_passing(const surge_grading *g, double d)
{
    if (d <= g->diameter_m[0])
        return d < g->diameter_m[0] ? 0 : g->passing[0];
    for (int k = 1; k < g->count; k++)
        if (d <= g->diameter_m[k]) {
            const double s = (d - g->diameter_m[k - 1]) / (g->diameter_m[k] - g->diameter_m[k - 1]);
            return g->passing[k - 1] + s * (g->passing[k] - g->passing[k - 1]);
        }
    return 1;
}

double surge_grading_inverse(const surge_grading *g, double d_min, double d_max, double u)
{
    const double p_min = surge_grading_passing(g, d_min), p_max = surge_grading_passing(g, d_max);
    if (!(d_max > d_min) || !(p_max > p_min))
        return NAN;
    const double target = p_min + u * (p_max - p_min);
    /* the segments of the curve inside [d_min, d_max], with the bounds as end points */
    double d0 = d_min, p0 = p_min;
    for (int k = 0; k <= g->count; k++) {
        const double d1 = k < g->count ? fmin(g->diameter_m[k], d_max) : d_max;
        if (d1 <= d0)
            continue;
        const double p1 = surge_grading_passing(g, d1);
        if (p1 >= target && p1 > p0)
            return d0 + (target - p0) / (p1 - p0) * (d1 - d0);
        d0 = d1, p0 = p1;
        if (d0 >= d_max)
            break;
    }
    return d_max;
}

/* ---- graded placement ---- */


static double standard_normal(unsigned short rng[3])
{
    const double u1 = 1.0 - erand48(rng), u2 = erand48(rng); /* u1 in (0, 1] */
    return sqrt(-2.0 * log(u1)) * cos(2.0 * pi * u2);
}

static int compare_descending(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x < y) - (x > y);
}

/* The graded placement's region: a disc's centre lies behind the front by a log-normal distance (truncated to the
 * block) and uniformly over the depth that keeps the gap from the bed and the surface */
typedef struct front_region {
    double x0, x1, depth, gap, log_median, sigma;
} front_region;

static int draw_behind_front(void *context, double r, unsigned short rng[3], double *x, double *y)
{
    const front_region *g = context;
    const double behind_m = exp(g->log_median + g->sigma * standard_normal(rng));
    *x = g->x1 - behind_m;
    *y = r + g->gap + (g->depth - 2 * (r + g->gap)) * erand48(rng);
    return *x < g->x0 + r + g->gap || *x > g->x1 - r - g->gap ? -1 : 0; /* the log-normal truncated to the block */
}

int surge_boulders_generate(const surge_params *p, surge_disc **out, char *err, size_t err_len)
{
    *out = NULL;
    const double dp = p->numerics.dp_m, depth = p->fluid.depth_m, x0 = p->fluid.x0_m, x1 = p->fluid.x1_m;
    const double gap = fmax(p->boulders.min_gap_m > 0 ? p->boulders.min_gap_m : dp, p->contacts.margin_dp * dp);
    const double period = p->domain.periodic_x ? p->domain.length_m : 0;
    const double d_min = p->boulders.diameter_min_m;
    const double d_max = p->boulders.diameter_max_m > 0 ? p->boulders.diameter_max_m : depth - 2 * gap;
    if (d_max > depth - 2 * gap + 1e-12) {
        snprintf(err, err_len, "boulders.diameter_max_m = %g m does not fit the fluid depth %g m with a gap of %g m "
                 "above and below (at most %g m)", d_max, depth, gap, depth - 2 * gap);
        return -1;
    }
    if (d_min < 3 * dp) {
        snprintf(err, err_len, "boulders: diameters between %g and %g m: diameter_min_m must be at least 3 dp = %g m "
                 "(a disc needs a few particles across): numerics.dp_m <= %g m, or a larger boulders.diameter_min_m",
                 d_min, d_max, 3 * dp, d_min / 3);
        return -1;
    }
    if (!(d_max > d_min)) {
        snprintf(err, err_len, "boulders: diameters between %g and %g m: diameter_max_m must be larger than "
                 "diameter_min_m", d_min, d_max);
        return -1;
    }
    if (p->boulders.count == 0 && !(p->boulders.solid_fraction > 0)) {
        snprintf(err, err_len, "graded boulders need boulders.count or boulders.solid_fraction above 0");
        return -1;
    }
    surge_grading *g = surge_grading_load(p->boulders.grading_file, err, err_len);
    if (!g)
        return -1;
    if (!(surge_grading_passing(g, d_max) > surge_grading_passing(g, d_min))) {
        snprintf(err, err_len, "the grading curve%s%s has no sizes between %g and %g m", p->boulders.grading_file[0] ?
                 " " : "", p->boulders.grading_file, d_min, d_max);
        surge_grading_free(g);
        return -1;
    }
    unsigned short rng[3] = {0x330e, (unsigned short)(p->boulders.seed & 0xffff),
                             (unsigned short)((unsigned)p->boulders.seed >> 16)};
    const double block_area = (x1 - x0) * depth, target_area = p->boulders.solid_fraction * block_area;
    double *diameters = malloc(sizeof(double) * MAX_DISCS), area = 0;
    int n = 0;
    while (diameters && n < MAX_DISCS) {
        if (p->boulders.count > 0 && n == p->boulders.count)
            break;
        const double d = surge_grading_inverse(g, d_min, d_max, erand48(rng)), a = 0.25 * pi * d * d;
        if (p->boulders.count == 0 && area + a - target_area > target_area - area)
            break; /* the last disc taken when it brings the area closer */
        diameters[n++] = d;
        area += a;
    }
    surge_grading_free(g);
    surge_disc *discs = diameters && n > 0 ? calloc((size_t)n, sizeof *discs) : NULL;
    if (!discs) {
        free(diameters);
        if (n == 0)
            snprintf(err, err_len, "boulders: solid_fraction %g of the fluid block holds no disc of %g m or more",
                     p->boulders.solid_fraction, d_min);
        else
            snprintf(err, err_len, "out of memory placing boulders");
        return -1;
    }
    qsort(diameters, (size_t)n, sizeof *diameters, compare_descending);
    double *radii = malloc(3 * sizeof(double) * (size_t)n);
    if (!radii) {
        free(diameters);
        free(discs);
        snprintf(err, err_len, "out of memory placing boulders");
        return -1;
    }
    double *xs = radii + n, *ys = radii + 2 * n;
    for (int i = 0; i < n; i++)
        radii[i] = 0.5 * diameters[i];
    free(diameters);
    const double sigma = p->boulders.front_sigma;
    front_region region = {x0, x1, depth, gap, log(p->boulders.front_median_m), sigma};
    const int placed = placement_sequential(radii, n, gap, period, 0, draw_behind_front, &region, rng,
                                            MAX_PLACEMENT_TRIES, xs, ys);
    for (int i = 0; i < placed; i++)
        discs[i] = (surge_disc){.x_m = xs[i], .y_m = ys[i], .r_m = radii[i]};
    free(radii);
    if (placed < n) {
        double placed_area = 0;
        for (int j = 0; j < placed; j++)
            placed_area += pi * discs[j].r_m * discs[j].r_m;
        snprintf(err, err_len, "boulders: placed %d of %d discs (%.3f of the fluid block's area, %.3f asked) in "
                 "%d random tries; ask for fewer discs, or spread them further from the front "
                 "(boulders.front_median_m %g m, front_sigma %g)", placed, n, placed_area / block_area,
                 area / block_area, MAX_PLACEMENT_TRIES, p->boulders.front_median_m, sigma);
        free(discs);
        return -1;
    }
    *out = discs;
    return n;
}

/* ---- the disc list as CSV ---- */

int surge_discs_write_csv(const char *path, const surge_disc *d, int count, char *err, size_t err_len)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    fprintf(f, "x_m,y_m,r_m,vx_mps,vy_mps,omega_radps\n");
    for (int i = 0; i < count; i++)
        fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", d[i].x_m, d[i].y_m, d[i].r_m, d[i].vx_mps, d[i].vy_mps,
                d[i].omega_radps);
    if (fclose(f) != 0) {
        snprintf(err, err_len, "cannot write '%s': %s", path, strerror(errno));
        return -1;
    }
    return 0;
}

int surge_discs_read_csv(const char *path, surge_disc **out, char *err, size_t err_len)
{
    *out = NULL;
    FILE *f = open_csv(path, "boulders.file", err, err_len);
    if (!f)
        return -1;
    static const char *const names[] = {"x_m", "y_m", "r_m", "vx_mps", "vy_mps", "omega_radps"};
    surge_disc *discs = malloc(sizeof *discs * MAX_DISCS);
    char buffer[LINE_BYTES];
    int line_number = 0, columns = 0, n = 0, ok = discs != NULL;
    if (!discs)
        snprintf(err, err_len, "out of memory");
    while (ok && fgets(buffer, sizeof buffer, f)) {
        line_number++;
        char *line = trimmed(buffer);
        if (!line)
            continue;
        if (!columns) {
            columns = header_is(line, names, 6) ? 6 : header_is(line, names, 3) ? 3 : -1;
            if (columns < 0) {
                snprintf(err, err_len, "%s:%d: the header must be 'x_m,y_m,r_m' or "
                         "'x_m,y_m,r_m,vx_mps,vy_mps,omega_radps', got '%.80s'", path, line_number, line);
                ok = 0;
            }
            continue;
        }
        double v[6] = {0};
        int bad = 0;
        const int got = csv_numbers(line, v, columns, &bad);
        if (got != columns) {
            snprintf(err, err_len, "%s:%d: expected %d numbers (%s), got '%.80s'", path, line_number, columns,
                     columns == 6 ? "x_m,y_m,r_m,vx_mps,vy_mps,omega_radps" : "x_m,y_m,r_m", line);
            ok = 0;
        } else if (!(v[2] > 0)) {
            snprintf(err, err_len, "%s:%d: radius %g m must be positive", path, line_number, v[2]);
            ok = 0;
        } else if (n == MAX_DISCS) {
            snprintf(err, err_len, "%s:%d: more than %d discs", path, line_number, MAX_DISCS);
            ok = 0;
        } else {
            discs[n++] = (surge_disc){v[0], v[1], v[2], v[3], v[4], v[5]};
        }
    }
    fclose(f);
    if (ok && n == 0) {
        snprintf(err, err_len, "%s holds no disc (a header x_m,y_m,r_m and one row per disc)", path);
        ok = 0;
    }
    if (!ok) {
        free(discs);
        return -1;
    }
    *out = discs;
    return n;
}
