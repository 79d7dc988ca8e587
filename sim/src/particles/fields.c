/* The per-particle fields driven by their lists (fields.h): allocation, the cell sort's permutation, the roll-back to
 * the step's start, the state hash and the checkpoint's particle block. */
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

typedef struct field_info {
    size_t offset;     /* of the array's pointer in struct surge_sim */
    size_t size;       /* of an element */
    int extent, roles; /* FIELD_ALL or FIELD_WALLS; FIELD_SORTED, ... */
} field_info;

#define FIELD_INFO(name, type, extent, roles, meaning) {offsetof(surge_sim, name), sizeof(type), extent, roles},
#define FIELD_COPY_INFO(name, type, extent, roles, meaning) {offsetof(surge_sim, name##_n), sizeof(type), extent, 0},
static const field_info fields[] = {SURGE_STEP_FIELDS(FIELD_INFO) SURGE_STEP_FIELDS(FIELD_COPY_INFO)
                                        SURGE_PARTICLE_FIELDS(FIELD_INFO)};
#define FIELD_COUNT (sizeof fields / sizeof fields[0])

static inline void **array_of(const surge_sim *sim, const field_info *f)
{
    return (void **)((char *)sim + f->offset);
}

int fields_allocate(surge_sim *sim)
{
    for (size_t i = 0; i < FIELD_COUNT; i++) {
        const size_t len = (size_t)(fields[i].extent == FIELD_WALLS ? sim->wall_count : sim->count);
        if (!(*array_of(sim, &fields[i]) = calloc(len > 0 ? len : 1, fields[i].size)))
            return -1;
    }
    return 0;
}

void fields_free(surge_sim *sim)
{
    for (size_t i = 0; i < FIELD_COUNT; i++)
        free(*array_of(sim, &fields[i]));
}

void fields_gather(void *array, size_t size, const int32_t *order, int first, int n, void *scratch)
{
    switch (size) {
    case 8: {
        uint64_t *a = array, *s = scratch;
        #pragma omp parallel for schedule(static)
        for (int i = 0; i < n; i++)
            s[i] = a[order[i]];
        break;
    }
    case 4: {
        uint32_t *a = array, *s = scratch;
        #pragma omp parallel for schedule(static)
        for (int i = 0; i < n; i++)
            s[i] = a[order[i]];
        break;
    }
    default: {
        char *a = array, *s = scratch;
        for (int i = 0; i < n; i++)
            memcpy(s + (size_t)i * size, a + (size_t)order[i] * size, size);
    }
    }
    memcpy((char *)array + (size_t)first * size, scratch, (size_t)n * size);
}

void fields_permute(surge_sim *sim, const int32_t *order, int first, int n, void *scratch)
{
    const int walls = first + n <= sim->wall_count;
    for (size_t i = 0; i < FIELD_COUNT; i++)
        if ((fields[i].roles & FIELD_SORTED) && (walls || fields[i].extent == FIELD_ALL))
            fields_gather(*array_of(sim, &fields[i]), fields[i].size, order, first, n, scratch);
}

void fields_restore_step_start(surge_sim *sim)
{
    const size_t w = (size_t)sim->wall_count, nf = (size_t)(sim->count - sim->wall_count);
#define RESTORE_FIELD(name, type, extent, roles, meaning) memcpy(sim->name + w, sim->name##_n + w, nf * sizeof(type));
    SURGE_STEP_FIELDS(RESTORE_FIELD)
#undef RESTORE_FIELD
}

uint64_t fields_fnv1a(uint64_t h, const void *data, size_t len)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < len; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

uint64_t fields_hash(const surge_sim *sim, uint64_t h)
{
    const size_t w = (size_t)sim->wall_count, nf = (size_t)(sim->count - sim->wall_count);
    for (size_t i = 0; i < FIELD_COUNT; i++)
        if (fields[i].roles & FIELD_HASHED)
            h = fields_fnv1a(h, (const char *)*array_of(sim, &fields[i]) + w * fields[i].size, nf * fields[i].size);
    return h;
}

size_t fields_checkpoint_bytes(void)
{
    size_t bytes = 0;
    for (size_t i = 0; i < FIELD_COUNT; i++)
        if (fields[i].roles & FIELD_CHECKPOINTED)
            bytes += fields[i].size;
    return bytes;
}

int fields_write(FILE *f, const surge_sim *sim)
{
    const size_t w = (size_t)sim->wall_count, nf = (size_t)(sim->count - sim->wall_count);
    for (size_t i = 0; i < FIELD_COUNT; i++)
        if ((fields[i].roles & FIELD_CHECKPOINTED) &&
            fwrite((const char *)*array_of(sim, &fields[i]) + w * fields[i].size, fields[i].size, nf, f) != nf)
            return -1;
    return 0;
}

int fields_read(FILE *f, surge_sim *sim)
{
    const size_t w = (size_t)sim->wall_count, nf = (size_t)(sim->count - sim->wall_count);
    for (size_t i = 0; i < FIELD_COUNT; i++)
        if ((fields[i].roles & FIELD_CHECKPOINTED) &&
            fread((char *)*array_of(sim, &fields[i]) + w * fields[i].size, fields[i].size, nf, f) != nf)
            return -1;
    return 0;
}
