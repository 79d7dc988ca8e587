#!/usr/bin/python3
"""surge_drift: a belt-surge run's consistency and its surge numbers (GMD eq. 21), snapshot by snapshot.

  tools/surge_drift.py RUN_DIR [--every 4] [--ignore-m 5] [--body-m 7] [--column-m 0.5] [--csv FILE]

For each --every-th snapshot (and the last), over the fluid more than --ignore-m from the upstream wall
(walls.upstream_x_m; the paper ignores the first 5 m):
- h_max: the highest column top (top particle + dp/2, columns --column-m wide), the paper's maximal flow height;
  h_vol: the largest fluid volume sum m/rho per unit length of a column (the height the densities say);
- u_bar: the mean x velocity of those particles relative to the belt;
- Fr = u_bar / sqrt(g h_max) and mu_eq/mu0 = g sin(theta) h_max^2 / (3 u_bar nu0) (eq. 21);
- kernel sum / density in the body: sum_b m W_ab (fluid and walls) over the particle's own density, for fluid
  particles from --ignore-m to --ignore-m + --body-m from the wall, more than 2h above the bed and 2h below
  their column's top; 1 when the particles sit as far apart as their densities say (tools/operator_check.py);
- the toe: the downstream end of the last column whose top exceeds 10 % of h_max;
- the lowest fluid particle's height above the bed face (negative: inside the wall).
Reads params.ini and the run's snap_*.vtp (python/surgepy/vtp.py); numpy only.
"""
import argparse
import glob
import math
import os
import sys

import numpy as np

from surgepy import cli_checks, vtp
from surgepy.run_params import ParamsError, RunParams
from operator_check import wendland

COLUMNS = ("t_s", "h_max_m", "h_vol_m", "u_bar_mps", "froude", "mu_eq_over_mu0", "kernel_sum_over_density",
           "body_particles", "toe_from_wall_m", "lowest_fluid_y_m")


def fail(message):
    cli_checks.fail("surge_drift", message)


def run_scales(run_dir):
    """The parameters the measures need, from params.ini; ParamsError naming what is wrong."""
    p = RunParams(run_dir)
    s = {"dp": p.positive("numerics", "dp_m"), "rho0": p.positive("fluid", "density_kgpm3"),
         "nu": p.positive("fluid", "viscosity_m2ps"), "g": p.positive("body", "gravity_mps2"),
         "theta": math.radians(p.real("body", "slope_deg")), "belt": p.real("walls", "bottom_speed_mps"),
         "wall_x": p.real("walls", "upstream_x_m"), "length": p.positive("domain", "length_m")}
    s["h"] = p.positive("numerics", "ch") * math.sqrt(2) * s["dp"]
    s["mass"] = s["rho0"] * s["dp"] ** 2
    return s


def measure(path, s, args):
    """One row (COLUMNS) for one snapshot; fails naming the file when it cannot be read or has no fluid past
    --ignore-m."""
    try:
        snap = vtp.read_vtp(path, ("time_s", "kind", "density_kgpm3", "velocity_mps"), finite=True)
    except vtp.VtpError as e:
        fail(str(e))
    x_all, y_all = snap["points"][:, 0], snap["points"][:, 1]
    fluid = snap["kind"] == 0
    x, y, rho = x_all[fluid], y_all[fluid], snap["density_kgpm3"][fluid]
    u = snap["velocity_mps"][fluid, 0] - s["belt"]
    from_wall = (x - s["wall_x"]) % s["length"]
    counted = from_wall > args.ignore_m
    if not counted.any():
        fail("%s: no fluid more than %g m from the upstream wall" % (path, args.ignore_m))
    edges = np.arange(args.ignore_m, from_wall.max() + args.column_m, args.column_m)
    column = np.digitize(from_wall, edges) - 1            # -1: within --ignore-m of the wall
    n_col = len(edges) - 1
    tops, volumes = np.zeros(n_col), np.zeros(n_col)
    for c in range(n_col):
        here = column == c
        if here.any():
            tops[c] = y[here].max() + 0.5 * s["dp"]
            volumes[c] = np.sum(s["mass"] / rho[here]) / args.column_m
    h_max, h_vol = tops.max(), volumes.max()
    wet = np.nonzero(tops > 0.1 * h_max)[0]
    toe = edges[wet.max() + 1]
    u_bar = u[counted].mean()
    froude = u_bar / math.sqrt(s["g"] * h_max)
    mu_ratio = s["g"] * math.sin(s["theta"]) * h_max ** 2 / (3 * u_bar * s["nu"])
    top_here = np.where(column >= 0, tops[np.clip(column, 0, n_col - 1)], 0)
    body = np.nonzero(counted & (from_wall < args.ignore_m + args.body_m) & (y > 2 * s["h"]) &
                      (y < top_here - 2 * s["h"]))[0]
    ratios = []
    for a in body:
        dx = x[a] - x_all
        dx -= s["length"] * np.round(dx / s["length"])
        q = np.hypot(dx, y[a] - y_all) / s["h"]
        ratios.append(np.sum(s["mass"] * wendland(q[q < 2], s["h"])) / rho[a])
    return (snap["time_s"], h_max, h_vol, u_bar, froude, mu_ratio, np.mean(ratios) if ratios else float("nan"),
            len(body), toe, y.min())


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir")
    parser.add_argument("--every", type=cli_checks.positive_int, default=4, help="every N-th snapshot (default 4)")
    parser.add_argument("--ignore-m", type=cli_checks.non_negative, default=5.0,
                        help="fluid this close to the upstream wall is left out (default 5 m, the paper's)")
    parser.add_argument("--body-m", type=cli_checks.positive, default=7.0,
                        help="length of the body zone for the kernel sum, from --ignore-m (default 7 m)")
    parser.add_argument("--column-m", type=cli_checks.positive, default=0.5, help="column width (default 0.5 m)")
    parser.add_argument("--csv", type=cli_checks.output_file, help="also write the rows to this CSV file")
    args = parser.parse_args()
    try:
        scales = run_scales(args.run_dir)
    except ParamsError as e:
        fail(str(e))
    files = sorted(glob.glob(os.path.join(args.run_dir, "snap_*.vtp")))
    if not files:
        fail("no snap_*.vtp in %s" % args.run_dir)
    chosen = files[::args.every] + ([files[-1]] if (len(files) - 1) % args.every else [])
    rows = [measure(path, scales, args) for path in chosen]
    print("%7s %7s %7s %7s %6s %7s %8s %5s %7s %9s" % ("t (s)", "h_max", "h_vol", "u_bar", "Fr", "mu/mu0",
                                                       "ks/rho", "n", "toe (m)", "y_min (m)"))
    for r in rows:
        print("%7.2f %7.3f %7.3f %7.3f %6.3f %7.3f %8.4f %5d %7.2f %9.4f" % r)
    if args.csv:
        try:
            with open(args.csv, "w") as f:
                f.write(",".join(COLUMNS) + "\n")
                for r in rows:
                    f.write(",".join("%.6g" % v for v in r) + "\n")
        except OSError as e:
            fail("--csv %s: cannot write it (%s)" % (args.csv, e.strerror or e))


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
