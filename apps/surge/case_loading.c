/* The case's parameters: the case file (or the built-in demo scene) with the -s overrides, validated. */
#include "cli.h"

#include <math.h>
#include <stdio.h>

#include "surge/render.h"
#include "surge/vtk_output.h"

extern const char surge_default_case_text[]; /* cases/demo.ini, embedded at build time */

/* An error found after the case parsed (a rule across parameters, the scene it builds) names the set of
 * parameters it came from. */
void print_case_error(const cli *c, const char *err)
{
    fprintf(stderr, "surge: %s%s: %s\n", c->case_path ? c->case_path : "cases/demo.ini (built in)",
            c->override_count ? " with the -s overrides" : "", err);
}

/* A periodic channel's particles tile its period, so dp must divide domain.length_m. A dp that does not is moved
 * to the nearest that does when that moves it by 1 % or less, and the move is said: changing dp alone then never
 * fails (the debris surge's 33 m refused dp = 0.035, 0.045 and 0.08 m). A larger move is left to the
 * validation's error, which names both numbers. */
static void fit_dp_to_period(surge_params *p)
{
    const double dp = p->numerics.dp_m, length_m = p->domain.length_m;
    if (!p->domain.periodic_x || !(dp > 0) || !(length_m > 0))
        return;
    const double spacings = length_m / dp, whole = round(spacings);
    if (fabs(spacings - whole) <= 1e-6 || whole < 1 || fabs(spacings / whole - 1) > 0.01)
        return;
    p->numerics.dp_m = length_m / whole;
    fprintf(stderr, "surge: note: numerics.dp_m = %g m does not divide the periodic domain.length_m = %g m (%.6g "
                    "spacings); using dp = %.9g m (%.0f spacings, %.2g %% %s) so that the particles tile the period\n",
            dp, length_m, spacings, p->numerics.dp_m, whole, 100 * fabs(p->numerics.dp_m / dp - 1),
            p->numerics.dp_m < dp ? "finer" : "coarser");
}

/* Loads the case (or the default scene) and applies overrides. */
int load_case(const cli *c, surge_params *p)
{
    char err[1024];
    *p = surge_default_params();
    int rc = c->case_path ? surge_params_load(p, c->case_path, err, sizeof err)
                          : surge_params_load_text(p, surge_default_case_text, "cases/demo.ini (built in)", err,
                                                   sizeof err);
    for (int i = 0; rc == 0 && i < c->override_count; i++)
        rc = surge_params_override(p, c->overrides[i], false, err, sizeof err);
    if (rc != 0) {
        fprintf(stderr, "surge: %s\n", err);
        return -1;
    }
    fit_dp_to_period(p);
    if (surge_params_validate(p, err, sizeof err) != 0) {
        print_case_error(c, err);
        return -1;
    }
    return 0;
}

/* render.height_px = 0: the height fitted to the scene, from the run's state (sim) or a saved snapshot (path). */
int fit_frame_height(surge_params *p, const surge_sim *sim, const char *path, char *err, size_t err_len)
{
    if (p->render.height_px > 0)
        return 0;
    surge_snapshot snap = {0};
    const int rc = sim ? (surge_sim_snapshot(sim, &snap) == 0 ? 0 : (snprintf(err, err_len, "out of memory"), -1))
                       : surge_vtp_read(path, &snap, err, err_len);
    if (rc == 0) {
        p->render.height_px = surge_render_fitted_height_px(p->render.width_px, &snap, p);
        fprintf(stderr, "surge: frames %d x %d px (height fitted to the scene; render.height_px sets it)\n",
                p->render.width_px, p->render.height_px);
    }
    surge_snapshot_free(&snap);
    return rc;
}
