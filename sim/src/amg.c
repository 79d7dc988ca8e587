/* hypre's BoomerAMG on one rank, as the preconditioner of the implicit scheme's own BiCGSTAB: one V-cycle per
 * application on a sparse stand-in of the operator (step_implicit.c). BoomerAMG's settings are those hypre
 * recommends for 2D problems on one rank with cheap setup: HMIS coarsening, extended+i interpolation with at most
 * 4 entries a row, strength threshold 0.5, one level of aggressive coarsening, hybrid forward Gauss-Seidel
 * smoothing (the hypre reference manual, "BoomerAMG"; on the Freydier front threshold 0.25, no aggressive level,
 * symmetric or l1 Gauss-Seidel were all slower, docs/method.md). hypre is built without threads here, so its
 * results do not depend on the thread count. */
#include "amg.h"

#include <mpi.h>
#include <stdio.h>
#include <stdlib.h>

#include "HYPRE.h"
#include "HYPRE_parcsr_ls.h"
#include "HYPRE_utilities.h"

/* the column indices are passed as they are (this build of hypre has 32-bit indices) */
_Static_assert(sizeof(HYPRE_BigInt) == sizeof(int32_t), "hypre built with 64-bit indices");

struct amg_system {
    int n;
    HYPRE_IJMatrix matrix;
    HYPRE_IJVector rhs, x;
    HYPRE_ParCSRMatrix a;      /* the objects behind matrix, rhs and x, as the solver takes them */
    HYPRE_ParVector b, xv;
    HYPRE_Solver multigrid;
    HYPRE_BigInt *rows;        /* 0 .. n-1 */
    HYPRE_Int *row_sizes;      /* per row: its entries */
};

static void finalize_mpi(void)
{
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!finalized)
        MPI_Finalize();
}

static void release(amg_system *amg)
{
    if (amg->multigrid)
        HYPRE_BoomerAMGDestroy(amg->multigrid);
    if (amg->matrix)
        HYPRE_IJMatrixDestroy(amg->matrix);
    if (amg->rhs)
        HYPRE_IJVectorDestroy(amg->rhs);
    if (amg->x)
        HYPRE_IJVectorDestroy(amg->x);
    amg->multigrid = NULL, amg->matrix = NULL, amg->rhs = amg->x = NULL;
}

amg_system *amg_create(char *err, size_t err_len)
{
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
        int provided = 0;
        if (MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
            snprintf(err, err_len, "implicit.preconditioner = amg: MPI (which hypre needs) did not start");
            return NULL;
        }
        atexit(finalize_mpi);
        HYPRE_Init();
    }
    amg_system *amg = calloc(1, sizeof *amg);
    if (!amg)
        snprintf(err, err_len, "out of memory for the multigrid solver");
    return amg;
}

void amg_destroy(amg_system *amg)
{
    if (!amg)
        return;
    release(amg);
    free(amg->rows);
    free(amg->row_sizes);
    free(amg);
}

int amg_setup(amg_system *amg, int n, const int64_t *row_first, const int32_t *cols, const double *values)
{
    release(amg);
    if (n > amg->n || !amg->rows) {
        HYPRE_BigInt *rows = realloc(amg->rows, (size_t)(n + 1) * sizeof *rows);
        HYPRE_Int *sizes = rows ? realloc(amg->row_sizes, (size_t)(n + 1) * sizeof *sizes) : NULL;
        if (rows)
            amg->rows = rows;
        if (!sizes)
            return -1;
        amg->row_sizes = sizes;
    }
    amg->n = n;
    for (int i = 0; i < n; i++)
        amg->rows[i] = i, amg->row_sizes[i] = (HYPRE_Int)(row_first[i + 1] - row_first[i]);
    HYPRE_ClearAllErrors();
    HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, n - 1, 0, n - 1, &amg->matrix);
    HYPRE_IJMatrixSetObjectType(amg->matrix, HYPRE_PARCSR);
    HYPRE_IJMatrixSetRowSizes(amg->matrix, amg->row_sizes);
    HYPRE_IJMatrixInitialize(amg->matrix);
    HYPRE_IJMatrixSetValues(amg->matrix, n, amg->row_sizes, amg->rows, (const HYPRE_BigInt *)cols, values);
    HYPRE_IJMatrixAssemble(amg->matrix);
    for (int k = 0; k < 2; k++) {
        HYPRE_IJVector *v = k ? &amg->x : &amg->rhs;
        HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, n - 1, v);
        HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
        HYPRE_IJVectorInitialize(*v);
        HYPRE_IJVectorAssemble(*v);
    }
    HYPRE_BoomerAMGCreate(&amg->multigrid);
    HYPRE_BoomerAMGSetPrintLevel(amg->multigrid, 0);
    HYPRE_BoomerAMGSetCoarsenType(amg->multigrid, 10);   /* HMIS */
    HYPRE_BoomerAMGSetInterpType(amg->multigrid, 6);     /* extended+i */
    HYPRE_BoomerAMGSetPMaxElmts(amg->multigrid, 4);
    HYPRE_BoomerAMGSetStrongThreshold(amg->multigrid, 0.5);
    HYPRE_BoomerAMGSetAggNumLevels(amg->multigrid, 1);
    HYPRE_BoomerAMGSetRelaxType(amg->multigrid, 3);      /* hybrid Gauss-Seidel, forward */
    HYPRE_BoomerAMGSetMaxIter(amg->multigrid, 1);
    HYPRE_BoomerAMGSetTol(amg->multigrid, 0.0);
    HYPRE_IJMatrixGetObject(amg->matrix, (void **)&amg->a);
    HYPRE_IJVectorGetObject(amg->rhs, (void **)&amg->b);
    HYPRE_IJVectorGetObject(amg->x, (void **)&amg->xv);
    HYPRE_BoomerAMGSetup(amg->multigrid, amg->a, amg->b, amg->xv);
    return HYPRE_GetError() ? -1 : 0;
}

int amg_vcycle(amg_system *amg, const double *rhs, double *x)
{
    if (!amg->multigrid)
        return -1;
    HYPRE_ClearAllErrors();
    HYPRE_IJVectorSetValues(amg->rhs, amg->n, amg->rows, rhs);
    HYPRE_ParVectorSetConstantValues(amg->xv, 0.0);
    HYPRE_BoomerAMGSolve(amg->multigrid, amg->a, amg->b, amg->xv);
    HYPRE_IJVectorGetValues(amg->x, amg->n, amg->rows, x);
    const int failed = HYPRE_GetError() != 0;
    HYPRE_ClearAllErrors();
    return failed ? -1 : 0;
}
