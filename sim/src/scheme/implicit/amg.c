/* hypre's BoomerAMG on one rank, as the preconditioner of the implicit scheme's own BiCGSTAB: one V-cycle per
 * application on a sparse stand-in of the operator (sim/src/scheme/implicit/). BoomerAMG's settings are those hypre
 * recommends for 2D problems on one rank with cheap setup: HMIS coarsening, extended+i interpolation with at most
 * 4 entries a row, strength threshold 0.5, one level of aggressive coarsening, hybrid forward Gauss-Seidel
 * smoothing (the hypre reference manual, "BoomerAMG"; on the Freydier front threshold 0.25, no aggressive level,
 * symmetric or l1 Gauss-Seidel were all slower, docs/method.md). hypre is built without threads here, so its
 * results do not depend on the thread count. A system that takes blocks of vectors (the viscous solve's two velocity
 * components) holds one copy of the hierarchy per block and V-cycles the blocks on their own threads, one copy
 * each: the same arithmetic as one copy block after block. With parts (amg_create), the matrix is cut into diagonal
 * blocks, a hierarchy each (and its copies), whose V-cycles run side by side: block Jacobi between the parts, the
 * same arithmetic whatever the thread count. The hierarchies of one part are built one after another, because
 * HMIS coarsening draws hypre's one global random sequence (reseeded at each build, so the copies are the same);
 * those of several parts take Ruge-Stueben coarsening, which draws none, and are built side by side, each hierarchy
 * on a communicator of its own (MPI allows no two threads a collective call on the same one). */
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
#define AMG_MAX_PARTS 256

/* One multigrid hierarchy on one part's diagonal block of the kept matrix, with its vectors */
typedef struct amg_copy {
    HYPRE_IJMatrix matrix;
    HYPRE_IJVector rhs, x;
    HYPRE_ParCSRMatrix a;      /* the objects behind matrix, rhs and x, as the solver takes them */
    HYPRE_ParVector b, xv;
    HYPRE_Solver multigrid;
    MPI_Comm comm;             /* its own duplicate of MPI_COMM_SELF, kept while the system lives */
} amg_copy;

struct amg_system {
    int n;
    int concurrent;            /* V-cycles may run on several threads at once (MPI allows it, threads exist) */
    int copies;                /* hierarchies held per part: one per block V-cycled at once (amg_create) */
    int parts_wanted;          /* the diagonal blocks asked for (amg_create) */
    int parts;                 /* those of the kept matrix: at most one per row */
    amg_copy *hierarchy;       /* copies x parts: copy c of part p at c * parts + p */
    MPI_Comm *comm;            /* copies x parts_wanted: the hierarchies' communicators, made as first needed */
    int comms;
    int *part_first;           /* parts + 1: part p's rows are the slots part_first[p] .. part_first[p+1] */
    int32_t *part_of_row;      /* per row: its part */
    int32_t *slot_of_row;      /* per row: its slot (part_first of its part + its row in the part's block) */
    int32_t *entry_of_slot;    /* per slot: the vector entry holding that row (amg_follow) */
    HYPRE_BigInt *slot_of_entry; /* its inverse: per vector entry, its slot */
    double *buffer;            /* copies x n: a part's vector in its own row order */
    HYPRE_BigInt *rows;        /* 0 .. n-1: a block's own row numbers */
    HYPRE_Int *row_sizes;      /* per slot: the entries of its row inside its block */
    int32_t *block_col;        /* the blocks' entries, slot after slot, columns numbered inside the block */
    double *block_val;
    int32_t *queue;            /* the partition's breadth-first order */
    int64_t *part_entry_first; /* parts + 1: part p's block entries are block_col/val[part_entry_first[p] ..] */
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
    const int held = amg->hierarchy ? amg->copies * amg->parts : 0;
    for (int c = 0; c < held; c++) {
        amg_copy *h = &amg->hierarchy[c];
        if (h->multigrid)
            HYPRE_BoomerAMGDestroy(h->multigrid);
        if (h->matrix)
            HYPRE_IJMatrixDestroy(h->matrix);
        if (h->rhs)
            HYPRE_IJVectorDestroy(h->rhs);
        if (h->x)
            HYPRE_IJVectorDestroy(h->x);
    }
    free(amg->hierarchy);
    amg->hierarchy = NULL;
    amg->parts = 0;
}

int amg_start(char *err, size_t err_len)
{
    int initialized = 0, provided = MPI_THREAD_SINGLE;
    MPI_Initialized(&initialized);
    if (initialized)
        return 0;
    /* MPI_THREAD_MULTIPLE: the hierarchies are built and V-cycled on several threads (on one rank, no messages) */
    if (MPI_Init_thread(NULL, NULL, MPI_THREAD_MULTIPLE, &provided) != MPI_SUCCESS) {
        snprintf(err, err_len, "implicit.preconditioner = amg: MPI (which hypre needs) did not start");
        return -1;
    }
    atexit(finalize_mpi);
    HYPRE_Init();
    return 0;
}

amg_system *amg_create(char *err, size_t err_len, int blocks, int parts)
{
    int provided = MPI_THREAD_SINGLE;
    if (amg_start(err, err_len) != 0)
        return NULL;
    MPI_Query_thread(&provided);
    amg_system *amg = calloc(1, sizeof *amg);
    if (!amg) {
        snprintf(err, err_len, "out of memory for the multigrid solver");
        return NULL;
    }
    const int concurrent = provided >= MPI_THREAD_MULTIPLE && omp_get_max_threads() > 1;
    amg->copies = concurrent && blocks > 1 ? (blocks < AMG_MAX_COPIES ? blocks : AMG_MAX_COPIES) : 1;
    amg->concurrent = concurrent;
    /* a system of several blocks (the viscous solve's two components) already runs that many V-cycles side by side:
     * it takes as many tasks in fewer parts */
    const int per_block = blocks > 1 ? (parts + blocks - 1) / blocks : parts;
    amg->parts_wanted = per_block < 1 ? 1 : per_block > AMG_MAX_PARTS ? AMG_MAX_PARTS : per_block;
    amg->comm = malloc((size_t)amg->copies * (size_t)amg->parts_wanted * sizeof *amg->comm);
    if (!amg->comm) {
        free(amg);
        snprintf(err, err_len, "out of memory for the multigrid solver");
        return NULL;
    }
    return amg;
}

void amg_destroy(amg_system *amg)
{
    if (!amg)
        return;
    release(amg);
    int finalized = 0;
    MPI_Finalized(&finalized);
    for (int c = 0; c < amg->comms && !finalized; c++)
        MPI_Comm_free(&amg->comm[c]);
    free(amg->comm);
    free(amg->part_first);
    free(amg->part_entry_first);
    free(amg->part_of_row);
    free(amg->slot_of_row);
    free(amg->entry_of_slot);
    free(amg->slot_of_entry);
    free(amg->buffer);
    free(amg->rows);
    free(amg->row_sizes);
    free(amg->block_col);
    free(amg->block_val);
    free(amg->queue);
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
        grow((void **)&amg->part_of_row, rows, sizeof *amg->part_of_row) ||
        grow((void **)&amg->slot_of_row, rows, sizeof *amg->slot_of_row) ||
        grow((void **)&amg->entry_of_slot, rows, sizeof *amg->entry_of_slot) ||
        grow((void **)&amg->slot_of_entry, rows, sizeof *amg->slot_of_entry) ||
        grow((void **)&amg->queue, rows, sizeof *amg->queue) ||
        grow((void **)&amg->buffer, rows * (size_t)amg->copies, sizeof *amg->buffer) ||
        grow((void **)&amg->part_first, (size_t)amg->parts_wanted + 1, sizeof *amg->part_first) ||
        grow((void **)&amg->part_entry_first, (size_t)amg->parts_wanted + 1, sizeof *amg->part_entry_first) ||
        grow((void **)&amg->row_id, rows, sizeof *amg->row_id) ||
        grow((void **)&amg->kept_first, rows, sizeof *amg->kept_first) ||
        grow((void **)&amg->row_of_id, (size_t)id_count, sizeof *amg->row_of_id))
        return -1;
    if (nnz > amg->kept_cap || !amg->kept_col) { /* an eighth to spare, as implicit_room_for */
        const size_t room = nnz + nnz / 8 + 64;
        if (grow((void **)&amg->kept_col, room, sizeof *amg->kept_col) ||
            grow((void **)&amg->kept_val, room, sizeof *amg->kept_val) ||
            grow((void **)&amg->block_col, room, sizeof *amg->block_col) ||
            grow((void **)&amg->block_val, room, sizeof *amg->block_val))
            return -1;
        amg->kept_cap = room;
    }
    amg->id_count = id_count;
    return 0;
}

/* Breadth-first order of the kept matrix's graph from start into amg->queue, each further connected piece from its
 * lowest row; returns the row reached last */
static int breadth_first(amg_system *amg, int n, int start)
{
    int32_t *seen = amg->slot_of_row, *queue = amg->queue; /* slot_of_row: scratch until partition() sets it */
    for (int i = 0; i < n; i++)
        seen[i] = 0;
    int head = 0, tail = 0, next_unseen = 0;
    while (tail < n) {
        if (head == tail) { /* a new connected piece */
            while (seen[next_unseen])
                next_unseen++;
            const int root = head == 0 && !seen[start] ? start : next_unseen;
            seen[root] = 1, queue[tail++] = root;
        }
        const int row = queue[head++];
        for (int64_t e = amg->kept_first[row]; e < amg->kept_first[row + 1]; e++)
            if (!seen[amg->kept_col[e]])
                seen[amg->kept_col[e]] = 1, queue[tail++] = amg->kept_col[e];
    }
    return queue[n - 1];
}

/* The rows shared out into parts of consecutive breadth-first order from a far row (the end of a first sweep, as
 * in reverse Cuthill-McKee): slices across the flow's longest extent, each part's rows kept in their own order */
static void partition(amg_system *amg, int n)
{
    const int parts = amg->parts = amg->parts_wanted < n ? amg->parts_wanted : n;
    if (parts > 1)
        breadth_first(amg, n, breadth_first(amg, n, 0));
    for (int k = 0; k < n; k++)
        amg->part_of_row[parts > 1 ? amg->queue[k] : k] = (int32_t)((int64_t)k * parts / n);
    for (int p = 0; p <= parts; p++)
        amg->part_first[p] = 0;
    for (int i = 0; i < n; i++)
        amg->part_first[amg->part_of_row[i] + 1]++;
    for (int p = 0; p < parts; p++)
        amg->part_first[p + 1] += amg->part_first[p];
    int32_t *next_slot = amg->queue; /* per part, free again: its rows take their slots in row order */
    for (int p = 0; p < parts; p++)
        next_slot[p] = amg->part_first[p];
    for (int i = 0; i < n; i++)
        amg->slot_of_row[i] = next_slot[amg->part_of_row[i]]++;
}

/* Hierarchy h on part p's diagonal block, whose entries start at block_col/val: Ruge-Stueben coarsening where
 * several parts are built side by side, HMIS where one is */
static void build_hierarchy(const amg_system *amg, amg_copy *h, int p, const int32_t *block_col, const double *block_val)
{
    const int first_slot = amg->part_first[p], rows = amg->part_first[p + 1] - first_slot;
    HYPRE_IJMatrixCreate(h->comm, 0, rows - 1, 0, rows - 1, &h->matrix);
    HYPRE_IJMatrixSetObjectType(h->matrix, HYPRE_PARCSR);
    HYPRE_IJMatrixSetRowSizes(h->matrix, amg->row_sizes + first_slot);
    HYPRE_IJMatrixInitialize(h->matrix);
    HYPRE_IJMatrixSetValues(h->matrix, rows, amg->row_sizes + first_slot, amg->rows, (const HYPRE_BigInt *)block_col,
                            block_val);
    HYPRE_IJMatrixAssemble(h->matrix);
    for (int k = 0; k < 2; k++) {
        HYPRE_IJVector *v = k ? &h->x : &h->rhs;
        HYPRE_IJVectorCreate(h->comm, 0, rows - 1, v);
        HYPRE_IJVectorSetObjectType(*v, HYPRE_PARCSR);
        HYPRE_IJVectorInitialize(*v);
        HYPRE_IJVectorAssemble(*v);
    }
    HYPRE_BoomerAMGCreate(&h->multigrid);
    HYPRE_BoomerAMGSetPrintLevel(h->multigrid, 0);
    HYPRE_BoomerAMGSetCoarsenType(h->multigrid, amg->parts > 1 ? 3 : 10); /* Ruge-Stueben with a third pass; HMIS */
    HYPRE_BoomerAMGSetInterpType(h->multigrid, 6);                         /* extended+i */
    HYPRE_BoomerAMGSetPMaxElmts(h->multigrid, 4);
    HYPRE_BoomerAMGSetStrongThreshold(h->multigrid, 0.5);
    HYPRE_BoomerAMGSetAggNumLevels(h->multigrid, 1);
    HYPRE_BoomerAMGSetRelaxType(h->multigrid, 3); /* hybrid Gauss-Seidel, forward */
    HYPRE_BoomerAMGSetKeepTranspose(h->multigrid, 1);
    HYPRE_BoomerAMGSetMaxIter(h->multigrid, 1);
    HYPRE_BoomerAMGSetTol(h->multigrid, 0.0);
    HYPRE_IJMatrixGetObject(h->matrix, (void **)&h->a);
    HYPRE_IJVectorGetObject(h->rhs, (void **)&h->b);
    HYPRE_IJVectorGetObject(h->x, (void **)&h->xv);
    HYPRE_BoomerAMGSetup(h->multigrid, h->a, h->b, h->xv);
}

/* The hierarchies on the kept matrix of n rows and row ids: one per part, on its diagonal block (the entries
 * between parts left out: block Jacobi between the parts) */
static int build(amg_system *amg, int n)
{
    release(amg);
    amg->n = n;
    for (int i = 0; i < amg->id_count; i++)
        amg->row_of_id[i] = -1;
    for (int i = 0; i < n; i++) {
        amg->rows[i] = i;
        amg->entry_of_slot[i] = -1;
        amg->row_of_id[amg->row_id[i]] = i;
    }
    partition(amg, n);
    const int parts = amg->parts, tasks = amg->copies * parts;
    amg->hierarchy = calloc((size_t)tasks, sizeof *amg->hierarchy);
    if (!amg->hierarchy) {
        amg->n = 0, amg->parts = 0;
        return -1;
    }
    for (; amg->comms < tasks; amg->comms++)
        if (MPI_Comm_dup(MPI_COMM_SELF, &amg->comm[amg->comms]) != MPI_SUCCESS) {
            release(amg);
            amg->n = 0;
            return -1;
        }
    for (int t = 0; t < tasks; t++)
        amg->hierarchy[t].comm = amg->comm[t];
    int32_t *row_of_slot = amg->queue; /* free again after the partition */
    for (int i = 0; i < n; i++)
        row_of_slot[amg->slot_of_row[i]] = i, amg->row_sizes[amg->slot_of_row[i]] = 0;
    if (parts == 1)
        for (int i = 0; i < n; i++)
            amg->row_sizes[i] = (HYPRE_Int)(amg->kept_first[i + 1] - amg->kept_first[i]);
    int64_t filled = 0;
    for (int p = 0; p < parts; p++) { /* the blocks' entries, part after part (one part: the kept matrix itself) */
        const int first_slot = amg->part_first[p], rows = amg->part_first[p + 1] - first_slot;
        amg->part_entry_first[p] = filled;
        for (int slot = first_slot; parts > 1 && slot < first_slot + rows; slot++) {
            const int i = row_of_slot[slot];
            for (int64_t e = amg->kept_first[i]; e < amg->kept_first[i + 1]; e++) {
                const int col = amg->kept_col[e];
                if (amg->part_of_row[col] == p) {
                    amg->block_col[filled] = amg->slot_of_row[col] - first_slot;
                    amg->block_val[filled++] = amg->kept_val[e];
                    amg->row_sizes[slot]++;
                }
            }
        }
    }
    const int32_t *col = parts == 1 ? amg->kept_col : amg->block_col;
    const double *val = parts == 1 ? amg->kept_val : amg->block_val;
    HYPRE_ClearAllErrors();
    #pragma omp parallel for schedule(dynamic, 1) if (amg->concurrent && parts > 1)
    for (int t = 0; t < tasks; t++) {
        const int p = t % parts;
        build_hierarchy(amg, &amg->hierarchy[t], p, col + amg->part_entry_first[p], val + amg->part_entry_first[p]);
    }
    if (HYPRE_GetError()) {
        release(amg);
        amg->n = 0;
        return -1;
    }
    for (int i = 0; i < n; i++) /* the vectors in row order until amg_follow says otherwise */
        amg->entry_of_slot[amg->slot_of_row[i]] = i, amg->slot_of_entry[i] = amg->slot_of_row[i];
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

int amg_rows(const amg_system *amg) { return amg && amg->hierarchy ? amg->n : 0; }

int amg_follow(amg_system *amg, const int32_t *id, int n)
{
    if (!amg->hierarchy || n != amg->n)
        return -1;
    for (int i = 0; i < n; i++) {
        const int row = id[i] >= 0 && id[i] < amg->id_count ? amg->row_of_id[id[i]] : -1;
        if (row < 0)
            return -1;
        amg->entry_of_slot[amg->slot_of_row[row]] = i, amg->slot_of_entry[i] = amg->slot_of_row[row];
    }
    return 0;
}

/* One V-cycle of hierarchy h on part p's slots of rhs into x, through buffer (one part: hypre places the entries
 * itself) */
static void part_vcycle(const amg_system *amg, const amg_copy *h, int p, double *buffer, const double *rhs, double *x)
{
    const int first = amg->part_first[p], rows = amg->part_first[p + 1] - first;
    const int32_t *entry = amg->entry_of_slot + first;
    if (amg->parts == 1)
        HYPRE_IJVectorSetValues(h->rhs, rows, amg->slot_of_entry, rhs);
    else {
        for (int j = 0; j < rows; j++)
            buffer[j] = rhs[entry[j]];
        HYPRE_IJVectorSetValues(h->rhs, rows, amg->rows, buffer);
    }
    HYPRE_ParVectorSetConstantValues(h->xv, 0.0);
    HYPRE_BoomerAMGSolve(h->multigrid, h->a, h->b, h->xv);
    if (amg->parts == 1) {
        HYPRE_IJVectorGetValues(h->x, rows, amg->slot_of_entry, x);
        return;
    }
    HYPRE_IJVectorGetValues(h->x, rows, amg->rows, buffer);
    for (int j = 0; j < rows; j++)
        x[entry[j]] = buffer[j];
}

int amg_vcycle(amg_system *amg, int blocks, const double *rhs, double *x)
{
    if (!amg->hierarchy)
        return -1;
    const int n = amg->n, parts = amg->parts, copies = amg->copies;
    /* hypre's error flag is one global: cleared before the hierarchies run and read after, so that no two threads
     * touch it but a failing V-cycle (whose flag either thread's failure sets) */
    HYPRE_ClearAllErrors();
    for (int k0 = 0; k0 < blocks; k0 += copies) { /* as many blocks at once as there are copies */
        const int at_once = blocks - k0 < copies ? blocks - k0 : copies, tasks = at_once * parts;
        #pragma omp parallel for schedule(dynamic, 1) if (amg->concurrent && tasks > 1)
        for (int t = 0; t < tasks; t++) {
            const int c = t / parts, p = t % parts, k = k0 + c;
            part_vcycle(amg, &amg->hierarchy[c * parts + p], p, amg->buffer + (size_t)c * n + amg->part_first[p],
                        rhs + (size_t)k * n, x + (size_t)k * n);
        }
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
