/* The registry of time-stepping schemes: numerics.scheme's value indexes it (params.c lists the names). */
#include "scheme/scheme.h"

static const time_scheme *const schemes[] = {
    [SURGE_SCHEME_EXPLICIT] = &scheme_explicit,
    [SURGE_SCHEME_IMPLICIT] = &scheme_implicit,
};

const time_scheme *scheme_of(const surge_params *p)
{
    return schemes[p->numerics.scheme];
}
