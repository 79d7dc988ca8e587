/* Owned particle-state snapshot: allocation helpers (see surge/snapshot.h). */
#include "surge/snapshot.h"

#include <stdlib.h>

/* Reallocates one array of snap to count elements; on failure leaves it untouched and clears ok. */
#define SNAPSHOT_GROW(snap, field, count, ok)                                                  \
    do {                                                                                       \
        if (ok) {                                                                              \
            void *grown_ = realloc((snap)->field, (size_t)(count) * sizeof *(snap)->field);    \
            if (grown_ != NULL) {                                                              \
                (snap)->field = grown_;                                                        \
            } else {                                                                           \
                (ok) = 0;                                                                      \
            }                                                                                  \
        }                                                                                      \
    } while (0)

int surge_snapshot_reserve(surge_snapshot *snap, int32_t count)
{
    if (snap == NULL || count < 0) {
        return -1;
    }
    if (count > snap->capacity) {
        /* Each successful realloc is stored at once, so a failure part-way leaves every array
         * valid and at least snap->capacity long; capacity is only raised when all succeeded. */
        int ok = 1;
        SNAPSHOT_GROW(snap, x_m, count, ok);
        SNAPSHOT_GROW(snap, y_m, count, ok);
        SNAPSHOT_GROW(snap, vx_mps, count, ok);
        SNAPSHOT_GROW(snap, vy_mps, count, ok);
        SNAPSHOT_GROW(snap, density_kgpm3, count, ok);
        SNAPSHOT_GROW(snap, pressure_pa, count, ok);
        SNAPSHOT_GROW(snap, kind, count, ok);
        SNAPSHOT_GROW(snap, id, count, ok);
        if (!ok) {
            return -1;
        }
        snap->capacity = count;
    }
    snap->count = count;
    return 0;
}

int surge_snapshot_reserve_boulders(surge_snapshot *snap, int32_t count)
{
    if (snap == NULL || count < 0) {
        return -1;
    }
    surge_boulder_state *b = &snap->boulders;
    if (count > b->capacity) {
        int ok = 1;
        SNAPSHOT_GROW(b, x_m, count, ok);
        SNAPSHOT_GROW(b, y_m, count, ok);
        SNAPSHOT_GROW(b, angle_rad, count, ok);
        SNAPSHOT_GROW(b, vx_mps, count, ok);
        SNAPSHOT_GROW(b, vy_mps, count, ok);
        SNAPSHOT_GROW(b, omega_radps, count, ok);
        SNAPSHOT_GROW(b, radius_m, count, ok);
        SNAPSHOT_GROW(b, fluid_fx_npm, count, ok);
        SNAPSHOT_GROW(b, fluid_fy_npm, count, ok);
        SNAPSHOT_GROW(b, film_fx_npm, count, ok);
        SNAPSHOT_GROW(b, film_fy_npm, count, ok);
        SNAPSHOT_GROW(b, wall_contact_fx_npm, count, ok);
        SNAPSHOT_GROW(b, wall_contact_fy_npm, count, ok);
        SNAPSHOT_GROW(b, disc_contact_fx_npm, count, ok);
        SNAPSHOT_GROW(b, disc_contact_fy_npm, count, ok);
        if (!ok) {
            return -1;
        }
        b->capacity = count;
    }
    b->count = count;
    return 0;
}

#undef SNAPSHOT_GROW

void surge_snapshot_free(surge_snapshot *snap)
{
    if (snap == NULL) {
        return;
    }
    free(snap->x_m);
    free(snap->y_m);
    free(snap->vx_mps);
    free(snap->vy_mps);
    free(snap->density_kgpm3);
    free(snap->pressure_pa);
    free(snap->kind);
    free(snap->id);
    snap->x_m = NULL;
    snap->y_m = NULL;
    snap->vx_mps = NULL;
    snap->vy_mps = NULL;
    snap->density_kgpm3 = NULL;
    snap->pressure_pa = NULL;
    snap->kind = NULL;
    snap->id = NULL;
    snap->capacity = 0;
    snap->count = 0;
    surge_boulder_state *b = &snap->boulders;
    free(b->x_m);
    free(b->y_m);
    free(b->angle_rad);
    free(b->vx_mps);
    free(b->vy_mps);
    free(b->omega_radps);
    free(b->radius_m);
    free(b->fluid_fx_npm);
    free(b->fluid_fy_npm);
    free(b->film_fx_npm);
    free(b->film_fy_npm);
    free(b->wall_contact_fx_npm);
    free(b->wall_contact_fy_npm);
    free(b->disc_contact_fx_npm);
    free(b->disc_contact_fy_npm);
    *b = (surge_boulder_state){0};
}
