/* Algebraic multigrid for the implicit scheme's solves: hypre's BoomerAMG, one V-cycle at a time as the
 * preconditioner of the scheme's own BiCGSTAB, on one MPI rank (docs/method.md, "Linear solvers"). */
#ifndef SURGE_AMG_H
#define SURGE_AMG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

typedef struct amg_system amg_system;

/* Starts MPI and hypre, once a process (about 0.4 s): the implicit scheme does it as it is created where its solves
 * use the multigrid, so that no step carries it. -1 when MPI cannot start (the message in err). */
int amg_start(char *err, size_t err_len);

/* NULL when MPI or hypre cannot start (the message in err). blocks: the vectors each amg_vcycle takes (1, or 2 for
 * two components); where threads allow, a hierarchy is held for each, so that their V-cycles run at once. parts: the
 * V-cycles each application runs side by side: the matrix is cut into parts / blocks diagonal blocks (rounded up), a
 * hierarchy each (block Jacobi between them; 1: the whole matrix). */
amg_system *amg_create(char *err, size_t err_len, int blocks, int parts);
void amg_destroy(amg_system *amg);

/* The matrix of n rows, row i's entries cols[row_first[i] .. row_first[i+1]) (no repeated column in a row), and
 * the multigrid hierarchy built on it; row i belongs to the particle row_id[i] (ids in [0, id_count)), so that the
 * hierarchy can serve later steps, whose particles are in another order (amg_follow). The matrix is kept (the
 * checkpoint's copy). -1 when out of memory or hypre reports an error. */
int amg_setup(amg_system *amg, int n, const int64_t *row_first, const int32_t *cols, const double *values,
              const int32_t *row_id, int id_count);

/* The rows of the hierarchy, 0 before a setup */
int amg_rows(const amg_system *amg);

/* Takes the vectors' entry i to be particle id[i] (n entries): -1 when n or an id does not match the rows. */
int amg_follow(amg_system *amg, const int32_t *id, int n);

/* One V-cycle of the hierarchy from zero on each of blocks consecutive vectors of amg_rows entries, x ~ A^-1 rhs,
 * in the order amg_follow last took; the same result whatever the thread count. -1 when hypre reports an error
 * (or no setup). */
int amg_vcycle(amg_system *amg, int blocks, const double *rhs, double *x);

/* The kept matrix and row ids, in binary (a checkpoint's block); amg_read sets the hierarchy up again from them,
 * the same as it was. -1 on a write or read error, or (amg_read) a matrix that is not one amg_setup takes. */
int amg_write(const amg_system *amg, FILE *f);
int amg_read(amg_system *amg, FILE *f, int id_count);

#endif
