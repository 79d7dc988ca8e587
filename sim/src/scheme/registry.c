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

const struct lubrication_share *film_share_of(const surge_params *p)
{
    switch (p->contacts.lubrication_share) {
    case SURGE_SHARE_EXPLICIT: return scheme_explicit.film_share;
    case SURGE_SHARE_IMPLICIT: return scheme_implicit.film_share;
    default: return scheme_of(p)->film_share;
    }
}
