#!/usr/bin/python3
"""How close the fluid comes to the walls of a belt scene, snapshot by snapshot: the measure behind the
belt-upstream-wall corner fix (docs/method.md) and the bed-layer packing of docs/validation/stability.md.

usage: wall_contact.py RUN_DIR [--after-s 0.5] [--every N]

For each snapshot (snap_*.vtp of RUN_DIR, every N-th), in units of dp:
  behind_wall  how far the fluid particle nearest the upstream wall is behind its face (x_w - min x) / dp:
               negative in front of it, 1 is where the health monitor stops the run;
  corner_y     the lowest fluid particle within 3 dp of the wall face and of the belt, over dp;
  corner_drho  the largest |rho/rho0 - 1| there;
  bed_y        the mean height over the belt of the fluid below 1 dp, in 100 mm bands from the wall, and within
               40 mm of the toe (dp/2 on the initial lattice).
Then the mean and extreme of behind_wall, corner_y and corner_drho over the snapshots after --after-s.
"""
import argparse
import glob
import os
import sys

import numpy as np

from surgepy import cli_checks
from surgepy.run_params import ParamsError, RunParams
from surgepy.vtp import VtpError, read_vtp


def fail(message):
    cli_checks.fail("wall_contact", message)


def run_parameters(run_dir):
    try:
        params = RunParams(run_dir)
        if not params.flag("walls", "upstream"):
            fail("%s: the scene has no upstream wall (walls.upstream = false)" % params.path)
        return (params.positive("numerics", "dp_m"), params.real("walls", "upstream_x_m"),
                params.positive("fluid", "density_kgpm3"))
    except ParamsError as e:
        fail(str(e))


def measure(snapshot, dp, x_wall, rho0):
    """One snapshot's distances (in dp) and the corner's density deviation; see the module's docstring."""
    try:
        d = read_vtp(snapshot, ("time_s", "kind", "density_kgpm3"), finite=True)
    except VtpError as e:
        fail(str(e))
    fluid = d["kind"] == 0
    if not np.any(fluid & (d["points"][:, 1] < 2 * dp)):
        fail("%s: no fluid particle within 2 dp of the belt" % snapshot)
    x, y = d["points"][fluid, 0], d["points"][fluid, 1]
    rho = d["density_kgpm3"][fluid]
    corner = (x < x_wall + 3 * dp) & (y < 3 * dp)
    bed = y < dp
    toe = x[y < 2 * dp].max()
    bands = [(x_wall + 0.1 * k, x_wall + 0.1 * (k + 1)) for k in range(int((toe - x_wall) / 0.1))]
    bands.append((toe - 0.04, toe + dp))
    bed_y = [float(y[bed & (x >= lo) & (x < hi)].mean() / dp) if np.any(bed & (x >= lo) & (x < hi)) else np.nan
             for lo, hi in bands]
    return {"time_s": d["time_s"], "behind_wall": (x_wall - x.min()) / dp,
            "corner_y": y[corner].min() / dp if corner.any() else np.nan,
            "corner_drho": np.abs(rho[corner] / rho0 - 1).max() if corner.any() else np.nan,
            "bands_mm": [(1e3 * lo, 1e3 * hi) for lo, hi in bands], "bed_y": bed_y}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir")
    ap.add_argument("--after-s", type=cli_checks.number, default=0.5)
    ap.add_argument("--every", type=cli_checks.positive_int, default=1)
    args = ap.parse_args()
    dp, x_wall, rho0 = run_parameters(args.run_dir)
    snapshots = sorted(glob.glob(os.path.join(args.run_dir, "snap_*.vtp")))[::args.every]
    if not snapshots:
        fail("%s: no snap_*.vtp snapshots" % args.run_dir)
    rows = [measure(s, dp, x_wall, rho0) for s in snapshots]
    for r in rows:
        bands = "  ".join("%.0f-%.0f:%.2f" % (lo, hi, v) for (lo, hi), v in zip(r["bands_mm"], r["bed_y"]))
        print("t %7.3f s  behind_wall %6.2f  corner_y %5.2f  corner_drho %.4f  bed_y [mm:dp] %s" %
              (r["time_s"], r["behind_wall"], r["corner_y"], r["corner_drho"], bands))
    late = [r for r in rows if r["time_s"] > args.after_s]
    if not late:
        fail("no snapshot after --after-s %g s (the last is at %g s)" % (args.after_s, rows[-1]["time_s"]))
    behind = np.array([r["behind_wall"] for r in late])
    corner = [r for r in late if np.isfinite(r["corner_y"])]
    if corner:
        drho = np.array([r["corner_drho"] for r in corner])
        corner_text = "corner_y min %.2f; corner_drho mean %.4f max %.4f (%d snapshots with corner fluid)" % (
            min(r["corner_y"] for r in corner), drho.mean(), drho.max(), len(corner))
    else:
        corner_text = "no fluid within 3 dp of the wall face and the belt"
    print("after %g s (%d snapshots): behind_wall mean %.2f max %.2f; %s" %
          (args.after_s, len(late), behind.mean(), behind.max(), corner_text))
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
