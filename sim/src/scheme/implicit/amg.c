/* hypre's BoomerAMG on one rank, as the preconditioner of the implicit scheme's own BiCGSTAB: one V-cycle per
 * application on a sparse stand-in of the operator (sim/src/scheme/implicit/). BoomerAMG's settings are those hypre
 * recommends for 2D problems on one rank with cheap setup: HMIS coarsening, extended+i interpolation with at most
 * 4 entries a row, strength threshold 0.5, one level of aggressive coarsening, hybrid forward Gauss-Seidel
 * smoothing (the hypre reference manual, "BoomerAMG"; on the Freydier front threshold 0.25, no aggressive level,
 * symmetric or l1 Gauss-Seidel were all slower, docs/method.md). hypre is built without threads here, so its
 * results do not depend on the thread count. A system that takes blocks of vectors (the viscous solve's two velocity
 * components) holds one copy of the hierarchy per block, built one after another on the same matrix (hypre's
 * coarsening reseeds its random numbers at each build, so the copies are the same), and V-cycles the blocks on
 * their own threads, one copy each: the same arithmetic as one copy block after block. */
#include "scheme/implicit/amg.h"

#include <math.h>
#include <mpi.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "HYPRE.h"
#include "HYPRE_parcsr_ls.h"
#include "HYPRE_utilities.h"

#define AMG_MAX_ROW_ENTRIES 1024 /* a checkpoint's matrix: more entries in a row than any kernel holds is corrupt */

/* the column indices are passed as they are (this build of hypre has 32-bit indices) */
_Static_assert(sizeof(HYPRE_BigInt) == sizeof(int32_t), "hypre built with 64-bit indices");

#define AMG_MAX_COPIES 2

/* One multigrid hierarchy on the kept matrix, with its vectors */
typedef struct amg_copy {
    HYPRE_IJMatrix matrix;
    HYPRE_IJVector rhs, x;
    HYPRE_ParCSRMatrix a;      /* the objects behind matrix, rhs and x, as the solver takes them */
    HYPRE_ParVector b, xv;
    HYPRE_Solver multigrid;
} amg_copy;

struct amg_system {
    int n;
    int copies;                /* hierarchies held: one per block V-cycled at once (amg_create) */
    amg_copy copy[AMG_MAX_COPIES];
    HYPRE_BigInt *rows;        /* 0 .. n-1 */
    HYPRE_Int *row_sizes;      /* per row: its entries */
    HYPRE_BigInt *order;       /* per vector entry: its particle's row (amg_follow) */
    int32_t *row_id;           /* per row: its particle's id */
    int32_t *row_of_id;        /* per id: its row, or -1 */
    int id_count;
    int64_t *kept_first;       /* the matrix the hierarchy was built on (amg_write) */
    int32_t *kept_col;
    double *kept_val;
    size_t kept_cap;
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
    for (int c = 0; c < AMG_MAX_COPIES; c++) {
        amg_copy *h = &amg->copy[c];
        if (h->multigrid)
            HYPRE_BoomerAMGDestroy(h->multigrid);
        if (h->matrix)
            HYPRE_IJMatrixDestroy(h->matrix);
        if (h->rhs)
            HYPRE_IJVectorDestroy(h->rhs);
        if (h->x)
            HYPRE_IJVectorDestroy(h->x);
        *h = (amg_copy){0};
    }
}

amg_system *amg_create(char *err, size_t err_len, int blocks)
{
    int initialized = 0, provided = MPI_THREAD_SINGLE;
    MPI_Initialized(&initialized);
    if (!initialized) {
        /* MPI_THREAD_MULTIPLE: the copies' V-cycles call MPI (on one rank, no messages) from their threads */
        if (MPI_Init_thread(NULL, NULL, MPI_THREAD_MULTIPLE, &provided) != MPI_SUCCESS) {
            snprintf(err, err_len, "implicit.preconditioner = amg: MPI (which hypre needs) did not start");
            return NULL;
        }
        atexit(finalize_mpi);
        HYPRE_Init();
    }
    MPI_Query_thread(&provided);
    amg_system *amg = calloc(1, sizeof *amg);
    if (!amg) {
        snprintf(err, err_len, "out of memory for the multigrid solver");
        return NULL;
    }
    const int concurrent = provided >= MPI_THREAD_MULTIPLE && omp_get_max_threads() > 1;
    amg->copies = concurrent && blocks > 1 ? (blocks < AMG_MAX_COPIES ? blocks : AMG_MAX_COPIES) : 1;
    return amg;
}

void amg_destroy(amg_system *amg)
{
    if (!amg)
        return;
    release(amg);
    free(amg->rows);
    free(amg->row_sizes);
    free(amg->order);
    free(amg->row_id);
    free(amg->row_of_id);
    free(amg->kept_first);
    free(amg->kept_col);
    free(amg->kept_val);
    free(amg);
}

static int grow(void **array, size_t count, size_t size)
{
    void *grown = realloc(*array, (count + 1) * size);
    if (!grown)
        return -1;
    *array = grown;
    return 0;
}

/* Room for n rows of nnz entries and ids in [0, id_count) */
static int reserve(amg_system *amg, int n, size_t nnz, int id_count)
{
    const size_t rows = (size_t)n + 1;
    if (grow((void **)&amg->rows, rows, sizeof *amg->rows) || grow((void **)&amg->row_sizes, rows, sizeof *amg->row_sizes) ||
        grow((void **)&amg->order, rows, sizeof *amg->order) || grow((void **)&amg->row_id, rows, sizeof *amg->row_id) ||
        grow((void **)&amg->kept_first, rows, sizeof *amg->kept_first) ||
        grow((void **)&amg->row_of_id, (size_t)id_count, sizeof *amg->row_of_id))
        return -1;
    if (nnz > amg->kept_cap || !amg->kept_col) {
        if (grow((void **)&amg->kept_col, nnz, sizeof *amg->kept_col) ||
            grow((void **)&amg->kept_val, nnz, sizeof *amg->kept_val))
            return -1;
        amg->kept_cap = nnz;
    }
    amg->id_count = id_count;
    return 0;
}

/* The hierarchy on the kept matrix of n rows and row ids; the entries in the rows' order */
static int build(amg_system *amg, int n)
{
    release(amg);
    amg->n = n;
    for (int i = 0; i < amg->id_count; i++)
        amg->row_of_id[i] = -1;
    for (int i = 0; i < n; i++) {
        amg->rows[i] = amg->order[i] = i;
        amg->row_sizes[i] = (HYPRE_Int)(amg->kept_first[i + 1] - amg->kept_first[i]);
        amg->row_of_id[amg->row_id[i]] = i;
    }
    HYPRE_ClearAllErrors();
    for (int c = 0; c < amg->copies; c++) { /* one after another: the coarsening's random numbers are global */
        amg_copy *h = &amg->copy[c];
        HYPRE_IJMatrixCreate(MPI_COMM_SELF, 0, n - 1, 0, n - 1, &h->matrix);
        HYPRE_IJMatrixSetObjectType(h->matrix, HYPRE_PARCSR);
        HYPRE_IJMatrixSetRowSizes(h->matrix, amg->row_sizes);
        HYPRE_IJMatrixInitialize(h->matrix);
        HYPRE_IJMatrixSetValues(h->matrix, n, amg->row_sizes, amg->rows, (const HYPRE_BigInt *)amg->kept_col,
                                amg->kept_val);
        HYPRE_IJMatrixAssemble(h->matrix);
        for (int k = 0; k < 2; k++) {
            HYPRE_IJVector *v = k ? &h->x : &h->rhs;
            HYPRE_IJVectorCreate(MPI_COMM_SELF, 0, n - 1, v);
            HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
            HYPRE_IJVectorInitialize(*v);
            HYPRE_IJVectorAssemble(*v);
        }
        HYPRE_BoomerAMGCreate(&h->multigrid);
        HYPRE_BoomerAMGSetPrintLevel(h->multigrid, 0);
        HYPRE_BoomerAMGSetCoarsenType(h->multigrid, 10);   /* HMIS */
        HYPRE_BoomerAMGSetInterpType(h->multigrid, 6);     /* extended+i */
        HYPRE_BoomerAMGSetPMaxElmts(h->multigrid, 4);
        HYPRE_BoomerAMGSetStrongThreshold(h->multigrid, 0.5);
        HYPRE_BoomerAMGSetAggNumLevels(h->multigrid, 1);
        HYPRE_BoomerAMGSetRelaxType(h->multigrid, 3);      /* hybrid Gauss-Seidel, forward */
        HYPRE_BoomerAMGSetKeepTranspose(h->multigrid, 1);
        HYPRE_BoomerAMGSetMaxIter(h->multigrid, 1);
        HYPRE_BoomerAMGSetTol(h->multigrid, 0.0);
        HYPRE_IJMatrixGetObject(h->matrix, (void **)&h->a);
        HYPRE_IJVectorGetObject(h->rhs, (void **)&h->b);
        HYPRE_IJVectorGetObject(h->x, (void **)&h->xv);
        HYPRE_BoomerAMGSetup(h->multigrid, h->a, h->b, h->xv);
    }
    if (HYPRE_GetError()) {
        release(amg);
        amg->n = 0;
        return -1;
    }
    return 0;
}

int amg_setup(amg_system *amg, int n, const int64_t *row_first, const int32_t *cols, const double *values,
              const int32_t *row_id, int id_count)
{
    const size_t nnz = (size_t)row_first[n];
    if (reserve(amg, n, nnz, id_count) != 0) {
        release(amg);
        amg->n = 0;
        return -1;
    }
    memcpy(amg->kept_first, row_first, (size_t)(n + 1) * sizeof *row_first);
    memcpy(amg->kept_col, cols, nnz * sizeof *cols);
    memcpy(amg->kept_val, values, nnz * sizeof *values);
    memcpy(amg->row_id, row_id, (size_t)n * sizeof *row_id);
    return build(amg, n);
}

int amg_rows(const amg_system *amg) { return amg && amg->copy[0].multigrid ? amg->n : 0; }

int amg_follow(amg_system *amg, const int32_t *id, int n)
{
    if (!amg->copy[0].multigrid || n != amg->n)
        return -1;
    for (int i = 0; i < n; i++) {
        const int row = id[i] >= 0 && id[i] < amg->id_count ? amg->row_of_id[id[i]] : -1;
        if (row < 0)
            return -1;
        amg->order[i] = row;
    }
    return 0;
}

int amg_vcycle(amg_system *amg, int blocks, const double *rhs, double *x)
{
    if (!amg->copy[0].multigrid)
        return -1;
    const int n = amg->n;
    /* hypre's error flag is one global: cleared before the copies run and read after, so that no two threads touch
     * it but a failing V-cycle (whose flag either thread's failure sets) */
    HYPRE_ClearAllErrors();
    #pragma omp parallel for num_threads(amg->copies) schedule(static, 1) if (amg->copies > 1 && blocks > 1)
    for (int k = 0; k < blocks; k++) {
        amg_copy *h = &amg->copy[k % amg->copies];
        HYPRE_IJVectorSetValues(h->rhs, n, amg->order, rhs + (size_t)k * n);
        HYPRE_ParVectorSetConstantValues(h->xv, 0.0);
        HYPRE_BoomerAMGSolve(h->multigrid, h->a, h->b, h->xv);
        HYPRE_IJVectorGetValues(h->x, n, amg->order, x + (size_t)k * n);
    }
    const int failed = HYPRE_GetError() != 0;
    HYPRE_ClearAllErrors();
    return failed ? -1 : 0;
}

static int write_all(FILE *f, const void *data, size_t len) { return fwrite(data, 1, len, f) == len ? 0 : -1; }
static int read_all(FILE *f, void *data, size_t len) { return fread(data, 1, len, f) == len ? 0 : -1; }

/* i32 rows n | (n > 0) row_id[i32 n] | row_first[i64 n+1] | cols[i32 nnz] | values[f64 nnz] */
int amg_write(const amg_system *amg, FILE *f)
{
    const int32_t n = amg_rows(amg);
    if (write_all(f, &n, 4) || n == 0)
        return n == 0 ? 0 : -1;
    const size_t nnz = (size_t)amg->kept_first[n];
    return write_all(f, amg->row_id, (size_t)n * sizeof *amg->row_id) ||
           write_all(f, amg->kept_first, (size_t)(n + 1) * sizeof *amg->kept_first) ||
           write_all(f, amg->kept_col, nnz * sizeof *amg->kept_col) ||
           write_all(f, amg->kept_val, nnz * sizeof *amg->kept_val) ? -1 : 0;
}

int amg_read(amg_system *amg, FILE *f, int id_count)
{
    int32_t n = 0;
    int64_t first = 0;
    release(amg);
    amg->n = 0;
    if (read_all(f, &n, 4) || n < 0 || n > id_count)
        return -1;
    if (n == 0)
        return 0;
    /* the row sizes first, then room for them: a corrupt count cannot ask for more than the file holds */
    if (reserve(amg, n, 0, id_count) || read_all(f, amg->row_id, (size_t)n * sizeof *amg->row_id) ||
        read_all(f, amg->kept_first, (size_t)(n + 1) * sizeof *amg->kept_first) || amg->kept_first[0] != 0)
        return -1;
    for (int i = 0; i < n; i++) {
        if (!(amg->kept_first[i + 1] > amg->kept_first[i] && amg->kept_first[i + 1] - amg->kept_first[i] <= AMG_MAX_ROW_ENTRIES))
            return -1;
        if (amg->row_id[i] < 0 || amg->row_id[i] >= id_count)
            return -1;
    }
    first = amg->kept_first[n];
    if (reserve(amg, n, (size_t)first, id_count) || read_all(f, amg->kept_col, (size_t)first * sizeof *amg->kept_col) ||
        read_all(f, amg->kept_val, (size_t)first * sizeof *amg->kept_val))
        return -1;
    for (int64_t e = 0; e < first; e++)
        if (amg->kept_col[e] < 0 || amg->kept_col[e] >= n || !isfinite(amg->kept_val[e]))
            return -1;
    for (int i = 0; i < id_count; i++)
        amg->row_of_id[i] = -1;
    for (int i = 0; i < n; i++) { /* the row ids must be distinct */
        if (amg->row_of_id[amg->row_id[i]] >= 0)
            return -1;
        amg->row_of_id[amg->row_id[i]] = i;
    }
    return build(amg, n);
}
