/* The totals of per-lane partial sums, eight at a time. A pair loop that keeps PAIR_LANES partial sums per quantity
 * (interaction.c) must add each quantity's lanes at the end; one by one that is PAIR_LANES scalar loads and adds
 * per quantity, which measured 14 % of the film's run time at C_h 1.0 (docs/performance.md). Here eight quantities'
 * lanes are transposed (24 shuffles) so that eight vector adds give all eight totals, each added in lane order
 * 0, 1, ..., 7 as the scalar loop did: the same bits. GCC's and Clang's vector extensions, no instruction set
 * named. */
#ifndef SURGE_LANES_H
#define SURGE_LANES_H

#include <stdint.h>
#include <string.h>

#include "precision.h"

/* The pair loops' vector width: every neighbour list is padded to a multiple of it (neighbours.c), so the loops run
 * whole vectors; the fluid pair loop (interaction.c) keeps one partial sum per lane, which measured faster than an
 * omp simd reduction (docs/performance.md) */
#define PAIR_LANES 8
_Static_assert(PAIR_LANES == 8, "lanes_totals transposes 8 x 8");

typedef real lanes_vector __attribute__((vector_size(PAIR_LANES * sizeof(real))));
#ifdef SURGE_DOUBLE_PAIRS
typedef int64_t lanes_mask __attribute__((vector_size(PAIR_LANES * sizeof(int64_t))));
#else
typedef int32_t lanes_mask __attribute__((vector_size(PAIR_LANES * sizeof(int32_t))));
#endif

/* A record read as one vector: any alignment of a real, and allowed to alias the record's struct. (A memcpy into a
 * vector, which GCC 12 made of two 16-byte copies through the stack when it targets AVX2, left each vector load
 * waiting on two stores it could not forward from: docs/performance.md, "How the pair loops are built, and what each
 * part gains".) */
typedef real lanes_vector_load __attribute__((vector_size(PAIR_LANES * sizeof(real)), aligned(sizeof(real)), may_alias));

#if defined(__clang__)
#define LANES_SHUFFLE(a, b, i0, i1, i2, i3, i4, i5, i6, i7) \
    __builtin_shufflevector(a, b, i0, i1, i2, i3, i4, i5, i6, i7)
#else
#define LANES_SHUFFLE(a, b, i0, i1, i2, i3, i4, i5, i6, i7) \
    __builtin_shuffle(a, b, (lanes_mask){i0, i1, i2, i3, i4, i5, i6, i7})
#endif

/* The 8 x 8 transpose: column[l][q] = row[q][l]. Interleaves neighbouring rows, then pairs of rows, then the
 * halves (24 shuffles). */
static inline void lanes_transpose(const lanes_vector row[8], lanes_vector column[8])
{
    const lanes_vector t0 = LANES_SHUFFLE(row[0], row[1], 0, 8, 1, 9, 4, 12, 5, 13);
    const lanes_vector t1 = LANES_SHUFFLE(row[0], row[1], 2, 10, 3, 11, 6, 14, 7, 15);
    const lanes_vector t2 = LANES_SHUFFLE(row[2], row[3], 0, 8, 1, 9, 4, 12, 5, 13);
    const lanes_vector t3 = LANES_SHUFFLE(row[2], row[3], 2, 10, 3, 11, 6, 14, 7, 15);
    const lanes_vector t4 = LANES_SHUFFLE(row[4], row[5], 0, 8, 1, 9, 4, 12, 5, 13);
    const lanes_vector t5 = LANES_SHUFFLE(row[4], row[5], 2, 10, 3, 11, 6, 14, 7, 15);
    const lanes_vector t6 = LANES_SHUFFLE(row[6], row[7], 0, 8, 1, 9, 4, 12, 5, 13);
    const lanes_vector t7 = LANES_SHUFFLE(row[6], row[7], 2, 10, 3, 11, 6, 14, 7, 15);
    const lanes_vector u0 = LANES_SHUFFLE(t0, t2, 0, 1, 8, 9, 4, 5, 12, 13);
    const lanes_vector u1 = LANES_SHUFFLE(t0, t2, 2, 3, 10, 11, 6, 7, 14, 15);
    const lanes_vector u2 = LANES_SHUFFLE(t1, t3, 0, 1, 8, 9, 4, 5, 12, 13);
    const lanes_vector u3 = LANES_SHUFFLE(t1, t3, 2, 3, 10, 11, 6, 7, 14, 15);
    const lanes_vector u4 = LANES_SHUFFLE(t4, t6, 0, 1, 8, 9, 4, 5, 12, 13);
    const lanes_vector u5 = LANES_SHUFFLE(t4, t6, 2, 3, 10, 11, 6, 7, 14, 15);
    const lanes_vector u6 = LANES_SHUFFLE(t5, t7, 0, 1, 8, 9, 4, 5, 12, 13);
    const lanes_vector u7 = LANES_SHUFFLE(t5, t7, 2, 3, 10, 11, 6, 7, 14, 15);
    column[0] = LANES_SHUFFLE(u0, u4, 0, 1, 2, 3, 8, 9, 10, 11);
    column[1] = LANES_SHUFFLE(u1, u5, 0, 1, 2, 3, 8, 9, 10, 11);
    column[2] = LANES_SHUFFLE(u2, u6, 0, 1, 2, 3, 8, 9, 10, 11);
    column[3] = LANES_SHUFFLE(u3, u7, 0, 1, 2, 3, 8, 9, 10, 11);
    column[4] = LANES_SHUFFLE(u0, u4, 4, 5, 6, 7, 12, 13, 14, 15);
    column[5] = LANES_SHUFFLE(u1, u5, 4, 5, 6, 7, 12, 13, 14, 15);
    column[6] = LANES_SHUFFLE(u2, u6, 4, 5, 6, 7, 12, 13, 14, 15);
    column[7] = LANES_SHUFFLE(u3, u7, 4, 5, 6, 7, 12, 13, 14, 15);
}

/* The records of entries index[0..7] of an array of records of 8 reals each (pair_state and the walls' records,
 * sim_internal.h), one vector load each, transposed: field[q][l] is the q-th field of entry l's record. Cheaper than
 * assembling each field from eight scalar loads, which is what GCC makes of record[index[l]].field in a vector
 * loop (docs/performance.md). */
static inline void lanes_gather_records(const void *records, const int32_t *index, lanes_vector field[8])
{
    const char *base = records;
    lanes_vector record[8];
    for (int l = 0; l < 8; l++)
        record[l] = *(const lanes_vector_load *)(base + (size_t)index[l] * sizeof(lanes_vector));
    lanes_transpose(record, field);
}

/* total[q] = lanes[q][0] + lanes[q][1] + ... + lanes[q][7], added in that order, for q = 0..7 */
static inline void lanes_totals(const real *const lanes[8], real total[8])
{
    lanes_vector v[8], column[8];
    for (int q = 0; q < 8; q++)
        v[q] = *(const lanes_vector_load *)lanes[q];
    lanes_transpose(v, column); /* column l: lane l of every quantity */
    lanes_vector sum = column[0];
    for (int l = 1; l < 8; l++)
        sum += column[l];
    memcpy(total, &sum, sizeof sum);
}

/* lane[0] + lane[1] + ... + lane[7], in that order: the total of a gather loop's PAIR_LANES partial sums of one
 * quantity in double (the implicit scheme's operators, whose sums in one chain waited on each add) */
static inline double lanes_total(const double lane[PAIR_LANES])
{
    double sum = lane[0];
    for (int l = 1; l < PAIR_LANES; l++)
        sum += lane[l];
    return sum;
}

#endif
