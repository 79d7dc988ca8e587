/* Contacts of rigid discs: grid broad phase, projected Gauss-Seidel on impulses with warm starting. See
 * contact_solver.h. Normal n points from body a to body b (a is the wall for disc-wall contacts); the
 * tangent is t = (-n_y, n_x). */
#include "boulders/contact_solver.h"
#include "boulders/lubrication.h"

#include <lapacke.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct contact {
    int64_t key;      /* (a, b) for warm starting */
    int a, b;         /* disc indices; a < 0: wall -1 - a */
    double nx, ny;
    double gap_m;     /* distance between the surfaces; < 0: overlap */
    double ra, rb;    /* lever arms (radii; 0 for a wall) */
    double k_n, k_t;  /* effective masses' inverses along n and t */
    double k_turn;    /* and along t for equal and opposite torques alone (the sliding film's) */
    double target_vn; /* smallest normal relative velocity allowed */
    double lambda_n, lambda_t; /* accumulated impulses */
    double lubrication;   /* the film's force per unit approach speed (lubrication.h); 0: none */
    double lubrication_t; /* and per unit sliding speed of the surfaces */
    double lambda_l, lambda_lt; /* their impulses in this sub-step */
    int reynolds;               /* lubrication_t is the tangential film's S (lubrication_tangential_matrix) */
    double lambda_r[4];         /* and its generalised impulse in this sub-step (reynolds_film) */
    double wall_vx, wall_vy;
} contact;

struct contact_solver {
    contact *now, *before;
    int now_count, before_count, capacity;
    int *cell_start, *cell_order, cell_capacity, order_capacity;
    contact_stats stats;
};

contact_solver *contact_solver_create(void) { return calloc(1, sizeof(contact_solver)); }

void contact_solver_destroy(contact_solver *s)
{
    if (!s)
        return;
    free(s->now);
    free(s->before);
    free(s->cell_start);
    free(s->cell_order);
    free(s);
}

contact_stats contact_solver_stats(const contact_solver *s) { return s->stats; }

int contact_solver_cache_count(const contact_solver *s) { return s->before_count; }

void contact_solver_cache_get(const contact_solver *s, int64_t *keys, double *lambda_n, double *lambda_t)
{
    for (int k = 0; k < s->before_count; k++) {
        keys[k] = s->before[k].key;
        lambda_n[k] = s->before[k].lambda_n;
        lambda_t[k] = s->before[k].lambda_t;
    }
}

int contact_solver_cache_set(contact_solver *s, int count, const int64_t *keys, const double *lambda_n,
                             const double *lambda_t)
{
    if (count > s->capacity) {
        contact *now = realloc(s->now, (size_t)count * sizeof *now), *before = NULL;
        if (now)
            s->now = now;
        if (!now || !(before = realloc(s->before, (size_t)count * sizeof *before)))
            return -1;
        s->before = before;
        s->capacity = count;
    }
    for (int k = 0; k < count; k++)
        s->before[k] = (contact){.key = keys[k], .lambda_n = lambda_n[k], .lambda_t = lambda_t[k]};
    s->before_count = count;
    return 0;
}

static int64_t contact_key(int a, int b) { return ((int64_t)(a + (1 << 20)) << 32) | (uint32_t)b; }

static int push_contact(contact_solver *s, contact c)
{
    if (s->now_count == s->capacity) {
        const int capacity = s->capacity ? 2 * s->capacity : 64;
        contact *now = realloc(s->now, (size_t)capacity * sizeof *now);
        if (!now)
            return -1;
        s->now = now;
        contact *before = realloc(s->before, (size_t)capacity * sizeof *before);
        if (!before)
            return -1;
        s->before = before;
        s->capacity = capacity;
    }
    s->now[s->now_count++] = c;
    return 0;
}

static double wrap_dx(double dx, double period)
{
    if (period > 0)
        dx -= period * floor(dx / period + 0.5);
    return dx;
}

/* Gap and normal (from the wall to the disc) of disc i against a wall. */
static double wall_gap(const contact_wall *w, double x, double y, double r, double period, double *nx, double *ny)
{
    if (w->shape == CONTACT_PLANE) {
        *nx = w->nx;
        *ny = w->ny;
        return w->nx * x + w->ny * y - w->offset - r;
    }
    const double ex = w->x1 - w->x0, ey = w->y1 - w->y0;
    const double px = wrap_dx(x - w->x0, period), py = y - w->y0;
    const double len2 = ex * ex + ey * ey;
    double u = len2 > 0 ? (px * ex + py * ey) / len2 : 0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    const double dx = px - u * ex, dy = py - u * ey, d = sqrt(dx * dx + dy * dy);
    if (d == 0) {
        *nx = 0;
        *ny = 1;
        return -r;
    }
    *nx = dx / d;
    *ny = dy / d;
    return d - r;
}

static int add_disc_pair(contact_solver *s, const contact_discs *d, int i, int j, double period, double margin)
{
    const double dx = wrap_dx(d->x[j] - d->x[i], period), dy = d->y[j] - d->y[i];
    const double dist = sqrt(dx * dx + dy * dy);
    const double gap = dist - d->radius[i] - d->radius[j];
    if (!(gap < margin) || dist == 0) /* a non-finite gap (a blown-up disc) is no contact */
        return 0;
    contact c = {.key = contact_key(i, j), .a = i, .b = j, .nx = dx / dist, .ny = dy / dist, .gap_m = gap,
                 .ra = d->radius[i], .rb = d->radius[j]};
    return push_contact(s, c);
}

enum { MAX_CELLS_PER_SIDE = 4096 };

/* A cell count clamped to [1, MAX_CELLS_PER_SIDE] before the cast, so that a disc flung far away or a
 * non-finite position (a blow-up the health monitor reports after this step) is safe. */
static int clamp_cells(double n)
{
    return n >= 1 ? (n < MAX_CELLS_PER_SIDE ? (int)n : MAX_CELLS_PER_SIDE) : 1;
}

/* The cell of a coordinate `offset` from the grid's origin, clamped to [0, n) (non-finite: cell 0). */
static int cell_of_offset(double offset, double cell_size, int n)
{
    const double c = floor(offset / cell_size);
    return c >= 0 ? (c < n ? (int)c : n - 1) : 0;
}

/* Candidate pairs from a uniform grid of cells at least one interaction range wide. */
static int find_disc_contacts(contact_solver *s, const contact_discs *d, double period, double margin)
{
    double r_max = 0, y_min = INFINITY, y_max = -INFINITY, x_min = INFINITY, x_max = -INFINITY;
    for (int i = 0; i < d->count; i++) {
        r_max = fmax(r_max, d->radius[i]);
        y_min = fmin(y_min, d->y[i]), y_max = fmax(y_max, d->y[i]);
        x_min = fmin(x_min, d->x[i]), x_max = fmax(x_max, d->x[i]);
    }
    const double width = 2 * r_max + margin;
    if (period > 0) {
        x_min = 0;
        x_max = period;
    }
    /* cells at least one interaction range wide, at most MAX_CELLS_PER_SIDE a side (wider cells then) */
    const int ncx = clamp_cells(period > 0 ? floor(period / width) : floor((x_max - x_min) / width) + 1);
    const double cell_w = period > 0 ? period / ncx : fmax(width, (x_max - x_min) / ncx * (1 + 1e-12));
    const int ncy = clamp_cells(floor((y_max - y_min) / width) + 1);
    const double cell_h = fmax(width, (y_max - y_min) / ncy * (1 + 1e-12));
    const int ncells = ncx * ncy;
    if (ncells + 1 > s->cell_capacity) {
        int *start = realloc(s->cell_start, (size_t)(ncells + 1) * sizeof *start);
        if (!start)
            return -1;
        s->cell_start = start;
        s->cell_capacity = ncells + 1;
    }
    if (d->count > s->order_capacity) {
        int *order = realloc(s->cell_order, (size_t)d->count * 2 * sizeof *order);
        if (!order)
            return -1;
        s->cell_order = order;
        s->order_capacity = d->count;
    }
    int *start = s->cell_start, *order = s->cell_order, *cell_of = s->cell_order + d->count;
    memset(start, 0, (size_t)(ncells + 1) * sizeof *start);
    for (int i = 0; i < d->count; i++) {
        const int cx = cell_of_offset(d->x[i] - x_min, cell_w, ncx), cy = cell_of_offset(d->y[i] - y_min, cell_h, ncy);
        cell_of[i] = cy * ncx + cx;
        start[cell_of[i] + 1]++;
    }
    for (int c = 0; c < ncells; c++)
        start[c + 1] += start[c];
    for (int i = 0; i < d->count; i++)
        order[start[cell_of[i]]++] = i;
    for (int c = ncells; c > 0; c--)
        start[c] = start[c - 1];
    start[0] = 0;

    for (int i = 0; i < d->count; i++) {
        const int cx = cell_of[i] % ncx, cy = cell_of[i] / ncx;
        int columns[3], ncol = 0;
        for (int k = -1; k <= 1; k++) {
            int col = cx + k;
            if (period > 0)
                col = (col + ncx) % ncx;
            else if (col < 0 || col >= ncx)
                continue;
            int seen = 0;
            for (int q = 0; q < ncol; q++)
                seen |= columns[q] == col;
            if (!seen)
                columns[ncol++] = col;
        }
        for (int row = cy - 1; row <= cy + 1; row++) {
            if (row < 0 || row >= ncy)
                continue;
            for (int q = 0; q < ncol; q++) {
                const int cell = row * ncx + columns[q];
                for (int k = start[cell]; k < start[cell + 1]; k++)
                    if (order[k] > i && add_disc_pair(s, d, i, order[k], period, margin) != 0)
                        return -1;
            }
        }
    }
    return 0;
}

/* Every pair of a disc and a wall or two discs whose gap is below margin, into s->now */
static int find_contacts(contact_solver *s, const contact_discs *d, const contact_wall *walls, int wall_count,
                         double period, double margin)
{
    s->now_count = 0;
    for (int i = 0; i < d->count; i++) {
        for (int w = 0; w < wall_count; w++) {
            double nx, ny;
            const double gap = wall_gap(&walls[w], d->x[i], d->y[i], d->radius[i], period, &nx, &ny);
            if (!(gap < margin)) /* non-finite: no contact */
                continue;
            contact c = {.key = contact_key(-1 - w, i), .a = -1 - w, .b = i, .nx = nx, .ny = ny, .gap_m = gap,
                         .rb = d->radius[i], .wall_vx = walls[w].vx_mps, .wall_vy = walls[w].vy_mps};
            if (push_contact(s, c) != 0)
                return -1;
        }
    }
    return find_disc_contacts(s, d, period, margin);
}

static int compare_keys(const void *a, const void *b)
{
    const int64_t ka = ((const contact *)a)->key, kb = ((const contact *)b)->key;
    return (ka > kb) - (ka < kb);
}

static const contact *find_before(const contact_solver *s, int64_t key)
{
    int lo = 0, hi = s->before_count - 1;
    while (lo <= hi) {
        const int mid = (lo + hi) / 2;
        if (s->before[mid].key == key)
            return &s->before[mid];
        if (s->before[mid].key < key)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return NULL;
}

/* Velocity of the contact point of b relative to that of a, along n and t. */
static void relative_velocity(const contact *c, const contact_discs *d, double *vn, double *vt)
{
    const double tx = -c->ny, ty = c->nx;
    double ux = d->vx[c->b] - d->omega[c->b] * c->rb * tx, uy = d->vy[c->b] - d->omega[c->b] * c->rb * ty;
    if (c->a >= 0) {
        ux -= d->vx[c->a] + d->omega[c->a] * c->ra * tx;
        uy -= d->vy[c->a] + d->omega[c->a] * c->ra * ty;
    } else {
        ux -= c->wall_vx;
        uy -= c->wall_vy;
    }
    *vn = ux * c->nx + uy * c->ny;
    *vt = ux * tx + uy * ty;
}

/* Impulse (pn n + pt t) on b at its contact point, the opposite on a. */
static void apply_impulse(const contact *c, contact_discs *d, double pn, double pt)
{
    const double px = pn * c->nx - pt * c->ny, py = pn * c->ny + pt * c->nx;
    d->vx[c->b] += d->inv_mass[c->b] * px;
    d->vy[c->b] += d->inv_mass[c->b] * py;
    d->omega[c->b] -= d->inv_inertia[c->b] * c->rb * pt;
    if (c->a >= 0) {
        d->vx[c->a] -= d->inv_mass[c->a] * px;
        d->vy[c->a] -= d->inv_mass[c->a] * py;
        d->omega[c->a] -= d->inv_inertia[c->a] * c->ra * pt;
    }
}

/* A contact's impulse of the sub-step on each disc's sums (contact_discs) */
static void add_disc_impulses(const contact *c, contact_discs *d)
{
    const double px = c->lambda_n * c->nx - c->lambda_t * c->ny, py = c->lambda_n * c->ny + c->lambda_t * c->nx;
    if (c->a < 0) {
        d->wall_impulse_x[c->b] += px;
        d->wall_impulse_y[c->b] += py;
        return;
    }
    d->disc_impulse_x[c->b] += px;
    d->disc_impulse_y[c->b] += py;
    d->disc_impulse_x[c->a] -= px;
    d->disc_impulse_y[c->a] -= py;
}

/* The torques of a tangential impulse pt at the contact point that the pressure's equal and opposite one at the
 * centres cancels the force of: each disc turned as by pt t on b and -pt t on a, neither moved */
static void apply_torques(const contact *c, contact_discs *d, double pt)
{
    d->omega[c->b] -= d->inv_inertia[c->b] * c->rb * pt;
    if (c->a >= 0)
        d->omega[c->a] -= d->inv_inertia[c->a] * c->ra * pt;
}

/* The widest gap a film acts across */
static double lubrication_reach_m(const contact_settings *set)
{
    return fmax(set->lubrication_cutoff_m, LUBRICATION_RESOLVED_END * set->lubrication_kernel_h_m);
}

/* The lubrication film's dampings of a contact, between the surfaces (radii and gap without the contact margin) */
static void film_dampings(contact *c, const contact_settings *set)
{
    const double rb = c->rb - 0.5 * set->gap_offset_m, ra = c->a >= 0 ? c->ra - 0.5 * set->gap_offset_m : 0;
    const double radius_m = c->a >= 0 ? ra * rb / (ra + rb) : rb, gap_m = c->gap_m + set->gap_offset_m;
    c->lubrication = lubrication_damping(set->lubrication_viscosity_pa_s, radius_m, gap_m, set->lubrication_cutoff_m,
                                         set->lubrication_min_gap_m);
    c->lubrication_t = lubrication_sliding_damping(set->lubrication_viscosity_pa_s, radius_m, gap_m,
                                                   set->lubrication_cutoff_m, set->lubrication_min_gap_m);
}

/* The measured squeeze film in place of the cut-off model's (settings' lubrication_kernel_h_m > 0), taken apart from
 * film_dampings so that the cut-off model's arithmetic compiles as before */
static void measured_squeeze_film(contact *c, const contact_settings *set)
{
    const double rb = c->rb - 0.5 * set->gap_offset_m, ra = c->a >= 0 ? c->ra - 0.5 * set->gap_offset_m : 0;
    c->lubrication = lubrication_measured_damping(set->lubrication_share, set->lubrication_viscosity_pa_s,
                                                  c->a >= 0 ? ra * rb / (ra + rb) : rb,
                                                  c->gap_m + set->gap_offset_m, set->lubrication_kernel_h_m,
                                                  set->lubrication_min_gap_m);
}

/* The tangential film's S in place of the sliding film's damping (contacts.lubrication_tangential = reynolds) */
static void tangential_film(contact *c, const contact_settings *set)
{
    const double rb = c->rb - 0.5 * set->gap_offset_m, ra = c->a >= 0 ? c->ra - 0.5 * set->gap_offset_m : 0;
    c->lubrication_t = lubrication_tangential_damping(set->lubrication_share, set->lubrication_viscosity_pa_s,
                                                      c->a >= 0 ? ra * rb / (ra + rb) : rb, c->gap_m + set->gap_offset_m,
                                                      set->lubrication_kernel_h_m, set->lubrication_min_gap_m);
}

static void prepare(contact_solver *s, contact_discs *d, const contact_settings *set, double h)
{
    for (int k = 0; k < s->now_count; k++) {
        contact *c = &s->now[k];
        const double inv_ma = c->a >= 0 ? d->inv_mass[c->a] : 0, inv_ia = c->a >= 0 ? d->inv_inertia[c->a] : 0;
        c->k_n = inv_ma + d->inv_mass[c->b];
        c->k_turn = c->ra * c->ra * inv_ia + c->rb * c->rb * d->inv_inertia[c->b];
        c->k_t = c->k_n + c->k_turn;
        double vn0, vt0;
        relative_velocity(c, d, &vn0, &vt0);
        /* Signorini at velocity level: close at most the gap in this sub-step, or open an overlap gradually */
        c->target_vn = c->gap_m > 0 ? -c->gap_m / h : set->erp * -c->gap_m / h;
        if (vn0 < -set->restitution_min_mps && -vn0 * h > c->gap_m)
            c->target_vn = fmax(c->target_vn, -set->restitution * vn0);
        film_dampings(c, set);
        c->lambda_l = 0, c->lambda_lt = 0, c->reynolds = 0;
        const contact *old = find_before(s, c->key);
        c->lambda_n = old ? old->lambda_n : 0;
        c->lambda_t = old ? old->lambda_t : 0;
        apply_impulse(c, d, c->lambda_n, c->lambda_t);
    }
    if (set->lubrication_kernel_h_m > 0)
        for (int k = 0; k < s->now_count; k++)
            measured_squeeze_film(&s->now[k], set);
    if (set->lubrication_kernel_h_m > 0 && set->lubrication_tangential_reynolds)
        for (int k = 0; k < s->now_count; k++) {
            contact *c = &s->now[k];
            tangential_film(c, set);
            c->reynolds = c->lubrication_t > 0;
            memset(c->lambda_r, 0, sizeof c->lambda_r);
        }
}

/* The tangential film (Reynolds'; lubrication_tangential_matrix) between disc b (T) and disc a or a wall (B), implicit
 * in the sub-step: its generalised impulse L = -h K q at the end velocities q = (U_T, Omega_T, U_B, Omega_B) along
 * t' = (n_y, -n_x) (a wall's q relative to its surface), so one Gauss-Seidel pass changes L by the d that solves
 * (I + h K W) d = -h K q - L, W the inverse masses and inertias of q */
static void reynolds_film(contact *c, contact_discs *d, double h)
{
    const double tx = c->ny, ty = -c->nx;
    double K[4][4], q[4] = {0}, w[4] = {0}, A[4][4], change[4];
    lapack_int pivots[4];
    lubrication_tangential_matrix(c->lubrication_t, c->rb, c->a >= 0 ? c->ra : 0, K);
    q[0] = d->vx[c->b] * tx + d->vy[c->b] * ty, q[1] = d->omega[c->b];
    w[0] = d->inv_mass[c->b], w[1] = d->inv_inertia[c->b];
    if (c->a >= 0) {
        q[2] = d->vx[c->a] * tx + d->vy[c->a] * ty, q[3] = d->omega[c->a];
        w[2] = d->inv_mass[c->a], w[3] = d->inv_inertia[c->a];
    } else {
        q[0] -= c->wall_vx * tx + c->wall_vy * ty;
    }
    for (int i = 0; i < 4; i++) { /* I + h K W is nonsingular: K symmetric positive semidefinite, W >= 0 diagonal */
        change[i] = -c->lambda_r[i];
        for (int j = 0; j < 4; j++) {
            A[i][j] = (i == j) + h * K[i][j] * w[j];
            change[i] -= h * K[i][j] * q[j];
        }
    }
    LAPACKE_dgesv(LAPACK_ROW_MAJOR, 4, 1, &A[0][0], 4, pivots, change, 1);
    d->vx[c->b] += w[0] * change[0] * tx, d->vy[c->b] += w[0] * change[0] * ty, d->omega[c->b] += w[1] * change[1];
    if (c->a >= 0) {
        d->vx[c->a] += w[2] * change[2] * tx, d->vy[c->a] += w[2] * change[2] * ty;
        d->omega[c->a] += w[3] * change[3];
    }
    for (int i = 0; i < 4; i++)
        c->lambda_r[i] += change[i];
}

static void solve(contact_solver *s, contact_discs *d, const contact_settings *set, double h)
{
    for (int it = 0; it < set->iterations; it++) {
        for (int k = 0; k < s->now_count; k++) {
            contact *c = &s->now[k];
            if (c->k_n <= 0)
                continue;
            double vn, vt;
            relative_velocity(c, d, &vn, &vt);
            if (c->lubrication > 0) {
                /* the film's impulse -c h vn at the sub-step's end velocity: vn + lambda_l / (c h) = 0 */
                const double compliance = 1.0 / (c->lubrication * h);
                const double delta = -(vn + c->lambda_l * compliance) / (c->k_n + compliance);
                apply_impulse(c, d, delta, 0);
                c->lambda_l += delta;
                relative_velocity(c, d, &vn, &vt);
            }
            if (c->reynolds) {
                reynolds_film(c, d, h);
                relative_velocity(c, d, &vn, &vt);
            } else if (c->lubrication_t > 0 && c->k_turn > 0) { /* the sliding film's torques, the same way */
                const double compliance = 1.0 / (c->lubrication_t * h);
                const double delta = -(vt + c->lambda_lt * compliance) / (c->k_turn + compliance);
                apply_torques(c, d, delta);
                c->lambda_lt += delta;
                relative_velocity(c, d, &vn, &vt);
            }
            const double lambda_n = fmax(0, c->lambda_n - (vn - c->target_vn) / c->k_n);
            apply_impulse(c, d, lambda_n - c->lambda_n, 0);
            c->lambda_n = lambda_n;
            relative_velocity(c, d, &vn, &vt);
            const double bound = set->friction * c->lambda_n;
            const double lambda_t = fmin(bound, fmax(-bound, c->lambda_t - vt / c->k_t));
            apply_impulse(c, d, 0, lambda_t - c->lambda_t);
            c->lambda_t = lambda_t;
        }
    }
}

int contact_solver_advance(contact_solver *s, contact_discs *d, const contact_wall *walls, int wall_count,
                           const contact_settings *set, double dt_s, const double *ax, const double *ay,
                           const double *alpha)
{
    const double h = dt_s / set->substeps, period = set->period_m;
    s->stats = (contact_stats){0};
    if (wall_count > CONTACT_WALLS_MAX)
        return -1;
    if (d->count == 0)
        return 0;
    if (d->wall_impulse_x)
        for (int i = 0; i < d->count; i++)
            d->wall_impulse_x[i] = d->wall_impulse_y[i] = d->disc_impulse_x[i] = d->disc_impulse_y[i] = 0;
    double r_min = INFINITY;
    for (int i = 0; i < d->count; i++)
        r_min = fmin(r_min, d->radius[i]);
    for (int sub = 0; sub < set->substeps; sub++) {
        double v_max = 0;
        for (int i = 0; i < d->count; i++) {
            d->vx[i] += h * (ax ? ax[i] : 0);
            d->vy[i] += h * (ay ? ay[i] : 0);
            const double damping = d->spin_damping ? d->spin_damping[i] : 0;
            d->omega[i] = (d->omega[i] + h * (alpha ? alpha[i] : 0)) / (1 + h * damping);
            if (d->inv_mass[i] == 0)
                d->vx[i] = d->vy[i] = 0;
            if (d->inv_inertia[i] == 0)
                d->omega[i] = 0;
            v_max = fmax(v_max, sqrt(d->vx[i] * d->vx[i] + d->vy[i] * d->vy[i]) + fabs(d->omega[i]) * d->radius[i]);
        }
        /* pairs that may touch within the sub-step, and those within the lubrication cut-off */
        double margin = 0.1 * r_min + 2 * h * v_max;
        if (set->lubrication_viscosity_pa_s > 0)
            margin = fmax(margin, lubrication_reach_m(set) - set->gap_offset_m);
        if (find_contacts(s, d, walls, wall_count, period, margin) != 0)
            return -1;
        for (int k = 0; k < s->now_count; k++)
            s->stats.max_overlap_m = fmax(s->stats.max_overlap_m, -s->now[k].gap_m);
        prepare(s, d, set, h);
        solve(s, d, set, h);
        for (int k = 0; k < s->now_count; k++) {
            const contact *c = &s->now[k];
            *(c->a < 0 ? &s->stats.wall_normal_impulse[-1 - c->a] : &s->stats.disc_normal_impulse) += c->lambda_n;
            *(c->a < 0 ? &s->stats.wall_friction_impulse[-1 - c->a] : &s->stats.disc_friction_impulse) +=
                fabs(c->lambda_t);
            if (d->wall_impulse_x)
                add_disc_impulses(c, d);
        }
        for (int i = 0; i < d->count; i++) {
            d->x[i] += h * d->vx[i];
            d->y[i] += h * d->vy[i];
            d->angle[i] += h * d->omega[i];
            if (period > 0) {
                d->x[i] -= period * floor(d->x[i] / period);
                if (d->x[i] >= period)
                    d->x[i] = 0;
            }
        }
        /* this sub-step's impulses warm-start the next */
        if (s->now_count > 1) /* qsort's array must not be NULL, even when empty */
            qsort(s->now, (size_t)s->now_count, sizeof *s->now, compare_keys);
        contact *swap = s->before;
        s->before = s->now;
        s->now = swap;
        s->before_count = s->now_count;
        s->stats.contacts = s->now_count;
    }
    return 0;
}

int contact_solver_films(contact_solver *s, const contact_discs *d, const contact_wall *walls, int wall_count,
                         const contact_settings *set, contact_film **films, int *count, int *capacity)
{
    *count = 0;
    if (d->count == 0 || !(set->lubrication_viscosity_pa_s > 0))
        return 0;
    if (find_contacts(s, d, walls, wall_count, set->period_m, lubrication_reach_m(set) - set->gap_offset_m) != 0)
        return -1;
    for (int k = 0; k < s->now_count; k++) {
        contact *c = &s->now[k];
        film_dampings(c, set);
        if (set->lubrication_kernel_h_m > 0)
            measured_squeeze_film(c, set);
        const int reynolds = set->lubrication_tangential_reynolds && set->lubrication_kernel_h_m > 0;
        if (reynolds)
            tangential_film(c, set);
        if (!(c->lubrication > 0) && !(c->lubrication_t > 0))
            continue;
        if (*count == *capacity) {
            const int grown = *capacity ? 2 * *capacity : 64;
            contact_film *more = realloc(*films, (size_t)grown * sizeof *more);
            if (!more)
                return -1;
            *films = more, *capacity = grown;
        }
        (*films)[(*count)++] = (contact_film){.a = c->a, .b = c->b, .nx = c->nx, .ny = c->ny, .ra = c->ra, .rb = c->rb,
                                              .normal_damping = c->lubrication, .sliding_damping = c->lubrication_t,
                                              .wall_vx = c->wall_vx, .wall_vy = c->wall_vy, .reynolds = reynolds};
    }
    s->now_count = 0;
    return 0;
}
