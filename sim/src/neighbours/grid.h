/* The cell grid: cells at least 2h wide, particles sorted by cell (grid.c). */
#ifndef SURGE_GRID_H
#define SURGE_GRID_H

#include <stddef.h>

#include "precision.h"

typedef struct surge_sim surge_sim;

/* Uniform cell grid, cells at least 2h wide, periodic in x or not. Wall particles (indices [0, wall_count))
 * and fluid particles ([wall_count, count)) are each sorted by cell and have their own cell ranges. */
typedef struct cell_grid {
    int ncx, ncy;
    double x0, y0;          /* lower-left corner */
    double cell_w, cell_h;
    double period_m;        /* > 0 when periodic in x */
    int *fluid_start;       /* ncx*ncy + 1 */
    int *wall_start;        /* ncx*ncy + 1 */
} cell_grid;

/* The particle index ranges of the 3x3 cells around a point, row by row, with the x shift that brings the
 * periodic image of a range next to the point. */
typedef struct neighbour_ranges {
    int count;
    int begin[6], end[6];
    double shift_x[6]; /* add to the neighbour's x */
} neighbour_ranges;

/* Up to two contiguous cell ranges per row of the 3x3 block around a cell, with the x shift that brings the
 * periodic image next to the particle. */
typedef struct cell_span {
    int first_cell, last_cell; /* inclusive, within one row */
    double shift_x;            /* add to the neighbour's x */
} cell_span;

int grid_init(surge_sim *sim, char *err, size_t err_len);
void grid_free(cell_grid *grid);
int grid_cell_x(const cell_grid *g, double x);
int grid_cell_y(const cell_grid *g, double y);
int grid_row_spans(const cell_grid *g, int cx, cell_span spans[2]);
/* start: the grid's fluid_start or wall_start; x inside the domain (wrapped when periodic). */
void grid_neighbour_ranges(const cell_grid *g, const int *start, double x, double y, neighbour_ranges *r);
/* Both kinds at once, for a loop over fluid and wall neighbours cell by cell. */
void grid_fluid_and_wall_ranges(const cell_grid *g, double x, double y, neighbour_ranges *fluid,
                                neighbour_ranges *walls);
/* Walls in cell order of their build positions, within a cell by id: the same order whatever the order before
 * (restarts). Fluid in cell order of the build positions, stable. */
void grid_sort_walls(surge_sim *sim);
void grid_sort_fluid(surge_sim *sim);

#endif
