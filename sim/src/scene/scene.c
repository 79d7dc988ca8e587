/* Building a scene from its parameters: walls of boundary particles with their mDBC ghost nodes, the
 * boulders' particles, the initial fluid block in hydrostatic balance (less what the boulders cover), and the
 * speed scale c0 derives from. */
#include <math.h>
#include <stdlib.h>

#include "physics/eos.h"
#include "sim_internal.h"
#include "boulders/boulders.h"
#include "scene/scales.h"
#include "scene/scene.h"

typedef struct particle_list {
    int32_t n, cap;
    int overflow; /* more particles than wall_capacity() planned: a bug, reported instead of dropping them */
    double *x, *y;
    real *gdx, *gdy;
    uint8_t *wall;
} particle_list;

static void push_wall(particle_list *l, double x, double y, double ghost_x, double ghost_y, int wall)
{
    if (l->n >= l->cap) {
        l->overflow = 1;
        return;
    }
    l->x[l->n] = x;
    l->y[l->n] = y;
    l->gdx[l->n] = (real)(ghost_x - x);
    l->gdy[l->n] = (real)(ghost_y - y);
    l->wall[l->n] = (uint8_t)wall;
    l->n++;
}

/* Wall particles of the box: bottom, top, left, right (corners mirrored through the corner point) and the
 * upstream wall. Ghost nodes are the particle mirrored across the wall face into the fluid. */
static void build_walls(const surge_params *p, particle_list *l)
{
    const double dp = p->numerics.dp_m, L = p->domain.length_m, H = p->domain.height_m;
    const int layers = p->walls.layers;
    const double depth = layers * dp;
    const double xlo = p->walls.left ? -depth : 0.0;
    const double xhi = p->walls.right ? L + depth : L;
    const long nx_ext = lround((xhi - xlo) / dp);
    for (int k = 0; k < layers; k++) {
        const double off = (k + 0.5) * dp;
        for (long i = 0; i < nx_ext; i++) {
            double x = xlo + (i + 0.5) * dp;
            double gx = x < 0 ? -x : (x > L ? 2 * L - x : x); /* corners mirror through the corner point */
            int bed = WALL_BOTTOM;
            const double xw = p->walls.upstream_x_m, back_m = scene_upstream_back_m(p);
            if (p->walls.upstream && x < xw && x > back_m) {
                /* bed under the upstream wall: the belt-wall corner, mirrored through the corner point of the face
                 * above it (the front's, or the back's behind the middle of the wall); it moves with the belt but its
                 * no-slip velocity is the fixed wall's (docs/method.md, "The belt–upstream-wall corner") */
                gx = x > xw - depth ? 2 * xw - x : 2 * back_m - x;
                bed = WALL_CORNER;
            }
            if (p->walls.bottom)
                push_wall(l, x, -off, gx, off, bed);
            if (p->walls.top)
                push_wall(l, x, H + off, gx, H - off, WALL_TOP);
        }
        const long ny = lround(H / dp);
        for (long j = 0; j < ny; j++) {
            double y = (j + 0.5) * dp;
            if (p->walls.left)
                push_wall(l, -off, y, off, y, WALL_FIXED);
            if (p->walls.right)
                push_wall(l, L + off, y, L - off, y, WALL_FIXED);
        }
        if (p->walls.upstream) {
            const long nu = lround(p->walls.upstream_height_m / dp);
            const double xw = p->walls.upstream_x_m, back_m = scene_upstream_back_m(p);
            const int back_face = back_m + off < xw - depth; /* this layer of the back face fits behind the front's */
            for (long j = 0; j < nu; j++) {
                double y = (j + 0.5) * dp;
                push_wall(l, xw - off, y, xw + off, y, WALL_FIXED);
                if (back_face)
                    push_wall(l, back_m + off, y, back_m - off, y, WALL_FIXED);
            }
        }
    }
}

/* Uniform depth that a belt moving at u_b holds steady on the slope: h_n = sqrt(3 nu u_b / (g sin theta)). */
static double uniform_depth(const surge_params *p)
{
    const double g_along = p->body.gravity_mps2 * sin(p->body.slope_deg * SURGE_PI / 180.0);
    return sqrt(3.0 * p->fluid.viscosity_m2ps * fabs(p->walls.bottom_speed_mps) / g_along);
}

/* Lubrication front (docs/references.md §2): xi tan(theta) / h_n = artanh(h/h_n) - h/h_n, xi upstream of the tip. */
static double lubrication_depth(double xi, double h_n, double tan_theta)
{
    const double target = xi * tan_theta / h_n;
    double lo = 0, hi = 1;
    for (int i = 0; i < 60; i++) {
        const double s = 0.5 * (lo + hi);
        if (atanh(s) - s < target)
            lo = s;
        else
            hi = s;
    }
    return 0.5 * (lo + hi) * h_n;
}

/* The initial fluid as columns of particles: rows[c] particles high in column c, from x0 (rows may be NULL); sites
 * (may be NULL): the rows of all columns together. Returns the number of columns, or -1 with a message. */
static long fluid_columns(const surge_params *p, int *rows, long max_columns, long long *sites, char *err,
                          size_t err_len)
{
    const double dp = p->numerics.dp_m;
    if (p->fluid.shape == SURGE_SHAPE_BLOCK) {
        const long cols = lround((p->fluid.x1_m - p->fluid.x0_m) / dp), column_rows = lround(p->fluid.depth_m / dp);
        for (long c = 0; rows && c < cols && c < max_columns; c++)
            rows[c] = (int)column_rows;
        if (sites)
            *sites = cols > 0 && column_rows > 0 ? (long long)cols * column_rows : 0;
        return cols;
    }
    const double theta = p->body.slope_deg * SURGE_PI / 180.0;
    if (p->walls.bottom_speed_mps == 0 || !(theta > 0) || p->fluid.viscosity_m2ps <= 0) {
        snprintf(err, err_len, "fluid.shape = lubrication needs a moving belt (walls.bottom_speed_mps), a positive "
                 "body.slope_deg and a viscosity");
        return -1;
    }
    const double h_n = uniform_depth(p), tan_theta = tan(theta);
    const double volume = (p->fluid.x1_m - p->fluid.x0_m) * p->fluid.depth_m;
    /* front length L with the block's volume: the integral of h over [0, L] from the tip */
    double length = 0, filled = 0;
    const double step = dp / 64;
    while (filled < volume && length < p->domain.length_m) {
        filled += lubrication_depth(length + 0.5 * step, h_n, tan_theta) * step;
        length += step;
    }
    const double x_tip = p->fluid.x0_m + length;
    if (x_tip > p->domain.length_m - 2.0 * dp) {
        snprintf(err, err_len, "fluid.shape = lubrication: the front (h_n = %.4g m) holding the block's volume would "
                 "reach x = %.4g m, beyond domain.length_m = %g", h_n, x_tip, p->domain.length_m);
        return -1;
    }
    /* rows from the cumulative volume, so that rounding each column does not bias the depth */
    const long cols = lround(length / dp);
    double volume_so_far = 0;
    long rows_so_far = 0;
    for (long c = 0; (rows || sites) && c < cols; c++) {
        volume_so_far += lubrication_depth(x_tip - (p->fluid.x0_m + (c + 0.5) * dp), h_n, tan_theta) * dp;
        const long total = lround(volume_so_far / (dp * dp));
        if (rows && c < max_columns)
            rows[c] = (int)(total - rows_so_far);
        rows_so_far = total;
    }
    if (sites)
        *sites = rows_so_far;
    return cols;
}

static int wall_capacity(const surge_params *p)
{
    const double dp = p->numerics.dp_m;
    const int layers = p->walls.layers;
    long n = 0;
    long nx_ext = lround(p->domain.length_m / dp) + 2 * layers + 2;
    n += (p->walls.bottom + p->walls.top) * nx_ext * layers;
    n += (p->walls.left + p->walls.right) * (lround(p->domain.height_m / dp) + 1) * layers;
    if (p->walls.upstream)
        n += (lround(p->walls.upstream_height_m / dp) + 1) * 2 * layers;
    return (int)n;
}

static int allocate_state(surge_sim *s, int n)
{
    s->count = n;
    int ok = fields_allocate(s) == 0 && boulders_allocate_wall_fields(&s->boulders, s->wall_count) == 0;
#define ALLOC(ptr, len) ok &= ((ptr) = calloc((size_t)(len) > 0 ? (size_t)(len) : 1, sizeof *(ptr))) != NULL
    ALLOC(s->sort_key, 2 * n); ALLOC(s->sort_scratch_i, n); ALLOC(s->sort_scratch_d, n);
#undef ALLOC
    return ok ? 0 : -1;
}

/* Row r (from the bed) of a fluid column of `rows` particles at rest: returns its hydrostatic density, the weight
 * of the rows above (rho0 g_n dp per row, half for its own) through the Tait inverse, and moves *y from row
 * r - 1's height (0 before row 0) to row r's. Rows sit dp rho0 / rho apart, so that each particle's area m / rho
 * is the area the lattice gives it and the kernel sum starts consistent with the density (docs/method.md). The
 * fluid of an incompressible scheme starts in rows dp apart at rho0. */
static double fluid_row(const surge_sim *s, long rows, long r, double g_normal, double *y)
{
    const double dp = s->params.numerics.dp_m;
    if (s->scheme->incompressible) { /* incompressible: every row at rho0, dp apart */
        *y = r == 0 ? 0.5 * dp : *y + dp;
        return s->rho0;
    }
    const double rho = tait_density(s->rho0 * g_normal * dp * (double)(rows - r - 0.5), s->rho0, s->b_pa);
    if (r == 0) {
        *y = 0.5 * dp * s->rho0 / rho;
    } else {
        const double rho_below = tait_density(s->rho0 * g_normal * dp * (double)(rows - r + 0.5), s->rho0, s->b_pa);
        *y += 0.5 * dp * (s->rho0 / rho_below + s->rho0 / rho);
    }
    return rho;
}

/* Whether lattice site (c, r) of the fluid block (columns of rows[c] rows from fluid.x0_m, row 0 on the bed), or the
 * point it would take, is filled at the start: a site of the block (a disc's too: the disc fills it) or a point inside
 * a wall. Not filled: beyond the block's free surface */
static int lattice_point_filled(const surge_params *p, const int *rows, long cols, long c, long r)
{
    const double dp = p->numerics.dp_m, length = p->domain.length_m;
    if (r < 0)
        return p->walls.bottom;
    double x = p->fluid.x0_m + (c + 0.5) * dp;
    const double y = (r + 0.5) * dp;
    if (p->domain.periodic_x)
        x -= floor(x / length) * length;
    const long k = (long)floor((x - p->fluid.x0_m) / dp);
    if (k >= 0 && k < cols && r < rows[k])
        return 1;
    if (p->walls.upstream && y < p->walls.upstream_height_m && x < p->walls.upstream_x_m &&
        x > p->walls.upstream_x_m - p->walls.layers * dp)
        return 1;
    return boulders_wall_face_distance_m(p, x, y) < 0;
}

/* Whether every lattice point within the kernel's support of site (c, r) is filled (lattice_point_filled): a site
 * whose kernel no free surface cuts, which the packing may move */
static int lattice_site_interior(const surge_sim *s, const int *rows, long cols, long c, long r)
{
    const double support_sites = 2.0 * s->derived.h_m / s->params.numerics.dp_m;
    const long reach = (long)ceil(support_sites);
    for (long dr = -reach; dr <= reach; dr++)
        for (long dc = -reach; dc <= reach; dc++)
            if ((double)(dc * dc + dr * dr) < support_sites * support_sites &&
                !lattice_point_filled(&s->params, rows, cols, c + dc, r + dr))
                return 0;
    return 1;
}

int scene_build(surge_sim *s, char *err, size_t err_len)
{
    const surge_params *p = &s->params;
    const double dp = p->numerics.dp_m;
    particle_list walls = {0};
    walls.cap = wall_capacity(p);
    walls.x = malloc((size_t)walls.cap * sizeof(double) + 1);
    walls.y = malloc((size_t)walls.cap * sizeof(double) + 1);
    walls.gdx = malloc((size_t)walls.cap * sizeof(real) + 1);
    walls.gdy = malloc((size_t)walls.cap * sizeof(real) + 1);
    walls.wall = malloc((size_t)walls.cap + 1);
    if (!walls.x || !walls.y || !walls.gdx || !walls.gdy || !walls.wall) {
        snprintf(err, err_len, "out of memory building walls");
        goto fail;
    }
    build_walls(p, &walls);
    if (walls.overflow) {
        snprintf(err, err_len, "internal error: the walls need more particles than planned (%d)", walls.cap);
        goto fail;
    }

    const long cols = fluid_columns(p, NULL, 0, NULL, err, err_len);
    int *rows = cols > 0 ? malloc((size_t)cols * sizeof *rows) : NULL;
    if (cols < 0 || !rows) {
        if (cols >= 0)
            snprintf(err, err_len, "out of memory");
        goto fail;
    }
    fluid_columns(p, rows, cols, NULL, err, err_len);
    const double theta = p->body.slope_deg * SURGE_PI / 180.0;
    const double g_normal = p->body.gravity_mps2 * cos(theta);
    long fluid_count = 0;
    for (long c = 0; c < cols; c++) {
        double y = 0;
        for (long r = 0; r < rows[c]; r++) {
            fluid_row(s, rows[c], r, g_normal, &y);
            fluid_count += !boulders_cover(s, p->fluid.x0_m + (c + 0.5) * dp, y);
        }
    }
    const int boulder_particles = boulders_particle_count(s);
    s->wall_count = walls.n + boulder_particles;
    if (s->scene_check && s->scene_check(s, s->wall_count, fluid_count, s->scene_check_user, err, err_len) != 0) {
        free(rows);
        goto fail;
    }
    if (allocate_state(s, s->wall_count + (int)fluid_count) != 0) {
        snprintf(err, err_len, "out of memory for %ld particles", (long)s->wall_count + fluid_count);
        free(rows);
        goto fail;
    }
    /* a new scene with discs is packed around them where asked (packing.c); a checkpoint's reader sets the positions */
    const int pack = s->boulders.count > 0 && p->boulders.pack_fluid && !s->scene_check;
    if (pack && !(s->pack_interior = calloc((size_t)fluid_count + 1, 1))) {
        snprintf(err, err_len, "out of memory for %ld particles", (long)s->wall_count + fluid_count);
        free(rows);
        goto fail;
    }
    for (int i = 0; i < s->wall_count; i++)
        s->boulders.of_wall[i] = -1;
    boulders_create_particles(s, walls.n);
    boulders_index_particles(s);
    boulders_place_particles(s);
    for (int i = 0; i < walls.n; i++) {
        s->x[i] = walls.x[i];
        s->y[i] = walls.y[i];
        s->rho[i] = (real)s->rho0;
        s->ghost_dx[i] = walls.gdx[i];
        s->ghost_dy[i] = walls.gdy[i];
        s->wall_of[i] = walls.wall[i];
        s->id[i] = i;
        s->kind[i] = SURGE_KIND_WALL; /* boundary_wall_speeds marks the moving ones, following live speeds */
    }
    /* fluid in columns dp apart, density in hydrostatic balance with the bed-normal gravity, rows as far apart
     * as that density says */
    int32_t i = s->wall_count;
    for (long c = 0; c < cols; c++) {
        double y = 0;
        for (long r = 0; r < rows[c]; r++) {
            const double rho = fluid_row(s, rows[c], r, g_normal, &y);
            if (boulders_cover(s, p->fluid.x0_m + (c + 0.5) * dp, y))
                continue;
            s->x[i] = p->fluid.x0_m + (c + 0.5) * dp;
            s->y[i] = y;
            s->rho[i] = (real)rho;
            /* the pressure at rest (the implicit scheme starts from it): the weight of the column above */
            s->pressure[i] = (real)(s->rho0 * g_normal * dp * ((double)rows[c] - 0.5 - (double)r));
            s->id[i] = i;
            s->kind[i] = SURGE_KIND_FLUID;
            if (pack)
                s->pack_interior[i - s->wall_count] = (uint8_t)lattice_site_interior(s, rows, cols, c, r);
            i++;
        }
    }
    free(rows);
    free(walls.x); free(walls.y); free(walls.gdx); free(walls.gdy); free(walls.wall);
    return 0;
fail:
    free(walls.x); free(walls.y); free(walls.gdx); free(walls.gdy); free(walls.wall);
    return -1;
}

int scene_count(const surge_params *params, long long *box_walls, long long *fluid_sites, char *err, size_t err_len)
{
    surge_params q = *params;
    q.walls.layers = surge_params_wall_layers(params); /* resolved as surge_sim_create does */
    const surge_params *p = &q;
    const double dp = p->numerics.dp_m, L = p->domain.length_m, depth = p->walls.layers * dp;
    /* as build_walls lays them */
    const double xlo = p->walls.left ? -depth : 0.0, xhi = p->walls.right ? L + depth : L;
    const long long nx_ext = fmax(0, lround((xhi - xlo) / dp)), ny = fmax(0, lround(p->domain.height_m / dp)),
                    nu = fmax(0, lround(p->walls.upstream_height_m / dp));
    long long walls = 0;
    for (int k = 0; k < p->walls.layers; k++) {
        walls += (p->walls.bottom + p->walls.top) * nx_ext + (p->walls.left + p->walls.right) * ny;
        if (p->walls.upstream)
            walls += nu * (1 + (scene_upstream_back_m(p) + (k + 0.5) * dp < p->walls.upstream_x_m - depth));
    }
    *box_walls = walls;
    return fluid_columns(p, NULL, 0, fluid_sites, err, err_len) < 0 ? -1 : 0;
}
