/* Algebraic multigrid for the implicit scheme's solves: hypre's BoomerAMG, one V-cycle at a time as the
 * preconditioner of the scheme's own BiCGSTAB, on one MPI rank (docs/method.md, "Linear solvers"). */
#ifndef SURGE_AMG_H
#define SURGE_AMG_H

#include <stddef.h>
#include <stdint.h>

typedef struct amg_system amg_system;

/* NULL when MPI or hypre cannot start (the message in err) */
amg_system *amg_create(char *err, size_t err_len);
void amg_destroy(amg_system *amg);

/* The matrix of n rows, row i's entries cols[row_first[i] .. row_first[i+1]) (no repeated column in a row), and
 * the multigrid hierarchy built on it; -1 when hypre reports an error. */
int amg_setup(amg_system *amg, int n, const int64_t *row_first, const int32_t *cols, const double *values);

/* One V-cycle of the hierarchy on rhs from zero, x ~ A^-1 rhs; -1 when hypre reports an error (or no setup). */
int amg_vcycle(amg_system *amg, const double *rhs, double *x);

#endif
