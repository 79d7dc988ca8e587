#!/usr/bin/python3
"""operator_check: how well the particles of a run still support the SPH operators, zone by zone.

  tools/operator_check.py RUN_DIR --x 0.06 0.12 --y 0.004 0.011 [--every 50] [--last 51]

For fluid particles in the box [x0, x1] x [y0, y1] (metres; choose it away from the bed and the free surface):
- per snapshot (every --every-th): the kernel-summed density sum_b m W_ab (fluid and walls) over the particle's
  own (continuity) density, and the kernel moment matrix M = sum_b V_b (r_b - r_a) (x) grad_a W_ab with
  V_b = m / rho_b. On a well-spaced set of particles both are 1; below 1, the particles are further apart than
  their densities say, and every SPH gradient and Laplacian is weaker by about that factor.
- over the last --last snapshots, for the fluid column over [x0, x1] (all heights): a quadratic fit of the
  belt-frame velocity u(y) = u0 + a y + b y^2, giving the slip u0 and the effective viscosity
  nu_eff = -g sin(theta) / (2 b) against the run's nu; and the vertical pressure gradient against hydrostatic
  rho0 g cos(theta). In a uniform film both ratios are 1.

Reads the run's params.ini and .vtp files (python/surgepy/vtp.py); numpy only.
"""
import argparse
import glob
import math
import os
import sys

import numpy as np

from surgepy import cli_checks, vtp
from surgepy.run_params import ParamsError, RunParams


def fail(message):
    cli_checks.fail("operator_check", message)


def wendland(q, h):
    """Quintic Wendland kernel W(q) in 2D, q = r / h < 2 (eq. 3)."""
    return 7 / (4 * math.pi * h * h) * (1 - q / 2) ** 4 * (2 * q + 1)


def kernel_sum_ratio(a, x, y, rho, mass, h, length):
    """sum_b m W_ab (all particles, periodic in x over length) over particle a's own density rho_a."""
    dx = x[a] - x
    dx -= length * np.round(dx / length)
    q = np.hypot(dx, y[a] - y) / h
    near = q < 2
    return np.sum(mass * wendland(q[near], h)) / rho[a]


def read_run(run_dir):
    """(params, dp, h, particle mass, period length) of a run folder; ParamsError naming what is wrong in params.ini."""
    params = RunParams(run_dir)
    dp, rho0 = params.positive("numerics", "dp_m"), params.positive("fluid", "density_kgpm3")
    h = params.positive("numerics", "ch") * math.sqrt(2) * dp
    return params, dp, h, rho0 * dp * dp, params.positive("domain", "length_m")


def zone(path, args):
    """(snapshot, fluid in the column over [x0, x1], fluid in the box) of one file; fails when the file cannot be
    read, holds non-finite values or no fluid particle in the box."""
    try:
        s = vtp.read_vtp(path, ("time_s", "kind", "density_kgpm3", "velocity_mps", "pressure_pa"), finite=True)
    except vtp.VtpError as e:
        fail(str(e))
    x, y = s["points"][:, 0], s["points"][:, 1]
    column = (s["kind"] == 0) & (x > args.x[0]) & (x < args.x[1])
    box = column & (y > args.y[0]) & (y < args.y[1])
    if not box.any():
        fail("%s: no fluid particle in the box x %g..%g m, y %g..%g m" % (path, *args.x, *args.y))
    return s, column, box


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir")
    parser.add_argument("--x", nargs=2, type=cli_checks.number, required=True, metavar=("X0", "X1"))
    parser.add_argument("--y", nargs=2, type=cli_checks.number, required=True, metavar=("Y0", "Y1"))
    parser.add_argument("--every", type=cli_checks.positive_int, default=50,
                        help="moment matrix of every N-th snapshot (default 50)")
    parser.add_argument("--last", type=cli_checks.positive_int, default=51,
                        help="snapshots for the profile fit (default 51)")
    args = parser.parse_args()
    if not (args.x[0] < args.x[1] and args.y[0] < args.y[1]):
        parser.error("the box must have X0 < X1 and Y0 < Y1")
    try:
        params, dp, h, mass, length = read_run(args.run_dir)
        rho0, nu = params.real("fluid", "density_kgpm3"), params.positive("fluid", "viscosity_m2ps")
        g, theta = params.positive("body", "gravity_mps2"), math.radians(params.real("body", "slope_deg"))
        belt = params.real("walls", "bottom_speed_mps")
    except ParamsError as e:
        fail(str(e))
    alpha = 7 / (4 * math.pi * h * h)
    files = sorted(glob.glob(os.path.join(args.run_dir, "snap_*.vtp")))
    if not files:
        fail("no snap_*.vtp in %s" % args.run_dir)

    print("operator_check: %s, zone x %g..%g m, y %g..%g m" % (args.run_dir, args.x[0], args.x[1], *args.y))
    print("%8s %10s %22s %10s %10s" % ("t (s)", "particles", "kernel sum / density", "M_xx", "M_yy"))
    for path in files[::args.every] + ([files[-1]] if (len(files) - 1) % args.every else []):
        s, _, box = zone(path, args)
        x, y, rho = s["points"][:, 0], s["points"][:, 1], s["density_kgpm3"]
        inside = np.where(box)[0]
        ratios, moment = [], np.zeros(2)
        for a in inside:
            dx = x[a] - x
            dx -= length * np.round(dx / length)
            dy = y[a] - y
            r = np.hypot(dx, dy)
            q = r / h
            near = q < 2
            ratios.append(np.sum(mass * wendland(q[near], h)) / rho[a])
            pair = near & (r > 0)
            factor = alpha / h * (-5 * q[pair] * (1 - q[pair] / 2) ** 3) / r[pair]   # grad_a W = factor r_ab
            volume = mass / rho[pair]
            moment += [np.sum(volume * dx[pair] ** 2 * -factor), np.sum(volume * dy[pair] ** 2 * -factor)]
        print("%8.2f %10d %22.4f %10.4f %10.4f" % (s["time_s"], len(inside), np.mean(ratios),
                                                 moment[0] / len(inside), moment[1] / len(inside)))

    heights, velocities, pressures, tops = [], [], [], []
    for path in files[-args.last:]:
        s, column, _ = zone(path, args)
        y = s["points"][:, 1]
        heights.append(y[column])
        velocities.append(s["velocity_mps"][column, 0] - belt)
        pressures.append(s["pressure_pa"][column])
        tops.append(y[column].max())
    y, u, p = np.concatenate(heights), np.concatenate(velocities), np.concatenate(pressures)
    u0, a, b = np.linalg.lstsq(np.vstack([np.ones_like(y), y, y * y]).T, u, rcond=None)[0]
    slope = np.polyfit(y, p, 1)[0]
    print("over the last %d snapshots, the column over x %g..%g m (top particle at %.2f mm on average):"
          % (min(args.last, len(files)), args.x[0], args.x[1], 1e3 * np.mean(tops)))
    print("  slip u(0) = %.2e m/s (belt frame); nu_eff / nu = %.3f; dp/dy over -rho0 g cos(theta) = %.3f"
          % (u0, -g * math.sin(theta) / (2 * b) / nu, -slope / (rho0 * g * math.cos(theta))))


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
