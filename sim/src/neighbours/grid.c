/* Cell-linked lists with particles sorted by cell: fluid particles at every neighbour-list build, wall particles
 * once (at every build when boulders move theirs). Cells are 2h + skin wide, so that a particle's 3 x 3 block holds
 * every neighbour within 2h as long as the lists built from it hold (neighbours.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"
#include "neighbours/grid.h"

int grid_init(surge_sim *sim, char *err, size_t err_len)
{
    const surge_params *p = &sim->params;
    cell_grid *g = &sim->grid;
    const double support = 2.0 * sim->derived.h_m + sim_neighbour_skin_m(sim);
    const double wall_depth = p->walls.layers * p->numerics.dp_m;
    if (p->domain.periodic_x) {
        g->period_m = p->domain.length_m;
        g->x0 = 0;
        g->ncx = (int)floor(p->domain.length_m / support);
        g->cell_w = p->domain.length_m / g->ncx;
    } else {
        g->period_m = 0;
        g->x0 = -wall_depth - support;
        g->ncx = (int)ceil((p->domain.length_m + 2.0 * (wall_depth + support)) / support);
        g->cell_w = support;
    }
    g->y0 = -wall_depth - support;
    g->cell_h = support;
    g->ncy = (int)ceil((p->domain.height_m + 2.0 * (wall_depth + support)) / support);
    if ((double)g->ncx * g->ncy > 2e8) {
        snprintf(err, err_len, "the cell grid would have %.3g cells: domain too large for numerics.dp_m",
                 (double)g->ncx * g->ncy);
        return -1;
    }
    size_t ncells = (size_t)g->ncx * (size_t)g->ncy;
    g->fluid_start = calloc(ncells + 1, sizeof(int));
    g->wall_start = calloc(ncells + 1, sizeof(int));
    if (!g->fluid_start || !g->wall_start) {
        snprintf(err, err_len, "out of memory for %zu cells", ncells);
        return -1;
    }
    return 0;
}

void grid_free(cell_grid *grid)
{
    free(grid->fluid_start);
    free(grid->wall_start);
    grid->fluid_start = grid->wall_start = NULL;
}

/* Clamped in floating point before the conversion, so that a position far outside (or NaN, which goes to cell 0)
 * never overflows an int. */
static int clamped_cell(double u, int n)
{
    const double c = floor(u);
    return !(c > 0) ? 0 : (c >= n ? n - 1 : (int)c);
}

int grid_cell_x(const cell_grid *g, double x)
{
    return clamped_cell((x - g->x0) / g->cell_w, g->ncx);
}

int grid_cell_y(const cell_grid *g, double y)
{
    return clamped_cell((y - g->y0) / g->cell_h, g->ncy);
}

int grid_row_spans(const cell_grid *g, int cx, cell_span spans[2])
{
    if (g->period_m <= 0) {
        spans[0] = (cell_span){cx > 0 ? cx - 1 : 0, cx < g->ncx - 1 ? cx + 1 : g->ncx - 1, 0.0};
        return 1;
    }
    if (cx == 0) {
        spans[0] = (cell_span){0, 1, 0.0};
        spans[1] = (cell_span){g->ncx - 1, g->ncx - 1, -g->period_m};
        return 2;
    }
    if (cx == g->ncx - 1) {
        spans[0] = (cell_span){g->ncx - 2, g->ncx - 1, 0.0};
        spans[1] = (cell_span){0, 0, g->period_m};
        return 2;
    }
    spans[0] = (cell_span){cx - 1, cx + 1, 0.0};
    return 1;
}

/* Fills r from start and, where other is not NULL, other_r from other_start: the same cells in the same order. */
static void fill_neighbour_ranges(const cell_grid *g, const int *start, const int *other_start, double x, double y,
                                  neighbour_ranges *r, neighbour_ranges *other_r)
{
    const int cx = grid_cell_x(g, x), cy = grid_cell_y(g, y);
    cell_span spans[2];
    const int nspans = grid_row_spans(g, cx, spans);
    r->count = 0;
    for (int row = cy - 1; row <= cy + 1; row++) {
        if (row < 0 || row >= g->ncy)
            continue;
        for (int s = 0; s < nspans; s++) {
            const int c0 = row * g->ncx + spans[s].first_cell, c1 = row * g->ncx + spans[s].last_cell + 1;
            r->begin[r->count] = start[c0];
            r->end[r->count] = start[c1];
            r->shift_x[r->count] = spans[s].shift_x;
            if (other_r) {
                other_r->begin[r->count] = other_start[c0];
                other_r->end[r->count] = other_start[c1];
                other_r->shift_x[r->count] = spans[s].shift_x;
            }
            r->count++;
        }
    }
    if (other_r)
        other_r->count = r->count;
}

void grid_neighbour_ranges(const cell_grid *g, const int *start, double x, double y, neighbour_ranges *r)
{
    fill_neighbour_ranges(g, start, NULL, x, y, r, NULL);
}

void grid_fluid_and_wall_ranges(const cell_grid *g, double x, double y, neighbour_ranges *fluid,
                                neighbour_ranges *walls)
{
    fill_neighbour_ranges(g, g->fluid_start, g->wall_start, x, y, fluid, walls);
}

/* Stable counting sort of particles [first, first+n) by the cell of their build position, visited in the order
 * visit gives (NULL: index order); fills start (ncells+1 entries, indices absolute) and writes the gather order
 * into order[0..n). */
static void counting_sort(const surge_sim *sim, int first, int n, const int32_t *visit, int *start, int32_t *key,
                          int32_t *order)
{
    const cell_grid *g = &sim->grid;
    const int ncells = g->ncx * g->ncy;
    memset(start, 0, (size_t)(ncells + 1) * sizeof(int));
    for (int i = 0; i < n; i++) {
        const double *xb = sim->neighbours.x_build, *yb = sim->neighbours.y_build;
        int k = grid_cell_y(g, yb[first + i]) * g->ncx + grid_cell_x(g, xb[first + i]);
        key[i] = k;
        start[k + 1]++;
    }
    start[0] = first;
    for (int c = 0; c < ncells; c++)
        start[c + 1] += start[c];
    for (int v = 0; v < n; v++) {
        const int i = visit ? visit[v] : v;
        order[start[key[i]]++ - first] = first + i;
    }
    /* start[c] now holds the end of cell c: shift back to beginnings */
    for (int c = ncells; c > 0; c--)
        start[c] = start[c - 1];
    start[0] = first;
}

/* The sorted fields (particles/fields.h) and the neighbour lists' build positions follow their particles */
static void permute(surge_sim *sim, const int32_t *order, int first, int n)
{
    fields_permute(sim, order, first, n, sim->sort_scratch_d);
    fields_gather(sim->neighbours.x_build, sizeof(double), order, first, n, sim->sort_scratch_d);
    fields_gather(sim->neighbours.y_build, sizeof(double), order, first, n, sim->sort_scratch_d);
}

void grid_sort_walls(surge_sim *sim)
{
    const int n = sim->wall_count;
    int32_t *order = sim->sort_key + sim->count; /* second half of the key buffer */
    int32_t *by_id = sim->sort_scratch_i;        /* wall ids are 0..n-1 */
    for (int i = 0; i < n; i++)
        by_id[sim->id[i]] = i;
    counting_sort(sim, 0, n, by_id, sim->grid.wall_start, sim->sort_key, order);
    permute(sim, order, 0, n);
}

void grid_sort_fluid(surge_sim *sim)
{
    const int first = sim->wall_count, n = sim->count - sim->wall_count;
    int32_t *order = sim->sort_key + sim->count;
    counting_sort(sim, first, n, NULL, sim->grid.fluid_start, sim->sort_key, order);
    permute(sim, order, first, n);
}
