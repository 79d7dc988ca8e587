/* surge check: a case validated and its scene built, without running it. */
#include "cli.h"

#include <stdio.h>

static const char *usage_check =
    "usage: surge check CASE [-s section.key=value ...]\n"
    "\n"
    "Reads and validates CASE (with overrides) and builds its scene without running it; prints the derived\n"
    "quantities (h, c0, particle counts) or the first error with file:line.\n";

/* What set c0: the parameter itself, the hydrostatic head, or the expected speed. */
static const char *c0_origin(const surge_params *resolved, const surge_derived *d)
{
    if (resolved->numerics.c0_mps > 0)
        return "set by numerics.c0_mps";
    if (d->c0_mps <= resolved->numerics.c0_factor * d->expected_speed_mps)
        return "set by the speed";
    return d->viscous_c0_mps > d->head_c0_mps ? "set by the discs' viscous pressures" : "set by the head";
}

int command_check(int argc, char **argv)
{
    if (wants_help(argc, argv)) {
        fputs(usage_check, stdout);
        return EXIT_OK;
    }
    cli c;
    if (parse_cli(argc, argv, &c, 0) != 0)
        return EXIT_USAGE;
    if (!c.case_path) {
        fprintf(stderr, "surge: check needs a CASE file\n%s", usage_check);
        return EXIT_USAGE;
    }
    surge_params p;
    if (load_case(&c, &p) != 0)
        return EXIT_USAGE;
    char err[1024];
    surge_sim *sim = surge_sim_create(&p, err, sizeof err);
    if (!sim) {
        print_case_error(&c, err);
        return EXIT_USAGE;
    }
    const surge_derived *d = surge_sim_derived(sim);
    printf("%s: ok: %d fluid + %d wall particles, h = %.6g m, c0 = %.6g m/s (%s; expected speed %.4g m/s; "
           "c0_factor x the hydrostatic head's speed sqrt(g H): %.4g m/s, 1 %% density at factor 10", c.case_path,
           d->fluid_count, d->wall_count, d->h_m, d->c0_mps, c0_origin(surge_sim_params(sim), d),
           d->expected_speed_mps, d->head_c0_mps);
    if (d->boulder_count > 0)
        printf("; c0_factor x the discs' viscous speed sqrt(nu u / r), r = %.4g m the smallest radius: %.4g m/s",
               d->smallest_boulder_radius_m, d->viscous_c0_mps);
    printf(")\n");
    report_resolution(sim, 1);
    warn_diffusive_compressibility(sim);
    surge_sim_destroy(sim);
    return EXIT_OK;
}
