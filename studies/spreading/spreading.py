#!/usr/bin/python3
"""A viscous current spreading on a no-slip bed (cases/viscous_spreading.ini): its front against the lubrication
model, and any film of fluid running ahead of it along the bed.

  studies/spreading/spreading.py measure RUN_DIR      # the front, snapshot by snapshot, against the model
  studies/spreading/spreading.py rows RUN_DIR [--time-s T]   # the first row's height by the current's depth
  studies/spreading/spreading.py reference CASE_OR_RUN_DIR [--times-s 1,2,5,10,20]

Model (docs/references.md): a creeping current on a horizontal bed, thin against its length, obeys
h_t = (g / (3 nu)) (h^3 h_x)_x (Huppert 1982). It is solved here by finite volumes (cells of depth/100, explicit steps
at 0.2 of the diffusion limit, no flux through the wall) from the case's block: depth_m deep from x0_m to x1_m against
the left wall, a film of 1e-8 depth elsewhere. Its front is the last cell deeper than 0.2 % of the block's depth.
Late in the current's life it approaches Huppert's similarity front x_N = 1.411 (g A^3 t / (3 nu))^(1/5), A the
block's area, printed beside it.

Measure, for each snapshot (x from the left wall's face, the bed's face at y = 0, in dp):
  toe    the fluid's largest x;
  body   the largest x of the fluid between 1 and 2 dp above the bed (the second row): the current's own front;
  film   fluid below 1 dp above the bed ahead of the body: how many particles, and how far the farthest lies ahead
         of the body (dp). A front that meets the bed has none or one; a film creeping ahead along the bed has many.
  row    the mean height above the bed of the fluid below 1 dp (the first row), in dp: 0.5 on the lattice.
Prints each snapshot's toe and body against the model at that time and their differences from it.

Rows, at the snapshot nearest T (default the last): the first row's mean height above the bed (dp) where the current
is how deep: its depth in a column 1 dp wide is the highest fluid particle's height plus half a spacing, in bands of
DEPTH_BANDS_DP; beside them the kernel's reach 2h in dp (h = C_h sqrt(2) dp), within which a particle's kernel meets
the free surface.
"""
import argparse
import os
import sys

import numpy as np

from surgepy import cli_checks, vtp
from surgepy.run_params import RunParams

TOOL = "spreading"
CELLS_PER_DEPTH = 100
FRONT_SHARE = 2e-3
PRECURSOR = 1e-8
SIMILARITY_ETA = 1.411


def fail(message):
    cli_checks.fail(TOOL, message)


def scene(params):
    """(g, nu, x0, x1, depth, length) of a spreading scene; ValueError naming the file and what does not fit."""
    g = params.positive("body", "gravity_mps2")
    if params.real("body", "slope_deg", 0.0) != 0:
        raise ValueError("%s: [body] slope_deg must be 0 (the model is a horizontal bed)" % params.path)
    nu = params.positive("fluid", "viscosity_m2ps")
    x0, x1 = params.real("fluid", "x0_m"), params.real("fluid", "x1_m")
    depth, length = params.positive("fluid", "depth_m"), params.positive("domain", "length_m")
    if not 0 <= x0 < x1 <= length:
        raise ValueError("%s: the block [fluid] x0_m = %g to x1_m = %g must lie in the domain's 0-%g m"
                         % (params.path, x0, x1, length))
    return g, nu, x0, x1, depth, length


def lubrication_fronts(g, nu, x0, x1, depth, length, times_s):
    """The model's front (m from the wall at x0) at each of times_s, ascending."""
    dx = depth / CELLS_PER_DEPTH
    n = max(2, int(round((length - x0) / dx)))
    x = (np.arange(n) + 0.5) * dx
    h = np.where(x < x1 - x0, depth, depth * PRECURSOR)
    k, t, fronts = g / (3 * nu), 0.0, []
    for end in times_s:
        while t < end:
            diffusivity = k * (0.5 * (h[1:] + h[:-1])) ** 3
            dt = min(0.2 * dx * dx / diffusivity.max(), end - t)
            flux = np.zeros(n + 1)
            flux[1:-1] = -diffusivity * (h[1:] - h[:-1]) / dx
            h -= dt * (flux[1:] - flux[:-1]) / dx
            t += dt
        wet = np.nonzero(h > FRONT_SHARE * depth)[0]
        fronts.append(x[wet[-1]] + 0.5 * dx)
    return fronts


def similarity_front(g, nu, area, t):
    return SIMILARITY_ETA * (g * area ** 3 * t / (3 * nu)) ** 0.2


def front_of(points, x0, dp):
    """(toe, body, film count, film reach, first row's height) of one snapshot's fluid positions (m; reach and
    height in dp; the height NaN where no fluid lies below 1 dp)"""
    x, y = points[:, 0] - x0, points[:, 1]
    second_row = (y >= dp) & (y < 2 * dp)
    body = x[second_row].max() if second_row.any() else x.min()
    film = (y < dp) & (x > body)
    reach = (x[film].max() - body) / dp if film.any() else 0.0
    first_row = y < dp
    height = float(y[first_row].mean() / dp) if first_row.any() else float("nan")
    return x.max(), body, int(film.sum()), reach, height


DEPTH_BANDS_DP = (0, 3, 5, 7, 10, 15, np.inf)  # rows: the current's local depth, dp


def first_row_by_depth(points, dp):
    """[(depth band low, high (dp), first-row particles, their mean height above the bed (dp))] of one snapshot's
    fluid positions (the bed's face at y = 0), bands without first-row particles left out"""
    x, y = points[:, 0], points[:, 1]
    column = np.floor(x / dp).astype(int)
    column -= column.min()
    top = np.full(column.max() + 1, -np.inf)
    np.maximum.at(top, column, y)
    depth_dp = top[column] / dp + 0.5
    first_row = y < dp
    bands = []
    for low, high in zip(DEPTH_BANDS_DP[:-1], DEPTH_BANDS_DP[1:]):
        inside = first_row & (depth_dp >= low) & (depth_dp < high)
        if inside.any():
            bands.append((low, high, int(inside.sum()), float(y[inside].mean() / dp)))
    return bands


def rows_command(folder, time_s):
    params = RunParams(folder)
    dp = params.positive("numerics", "dp_m")
    reach_dp = 2 * params.positive("numerics", "ch") * np.sqrt(2)
    snapshots = [(t, name) for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd")) if t > 0]
    if not snapshots:
        raise ValueError("%s: no snapshot after t = 0" % folder)
    t, name = min(snapshots, key=lambda e: abs(e[0] - time_s)) if time_s is not None else snapshots[-1]
    s = vtp.read_vtp(os.path.join(folder, name), ("kind",), finite=True)
    fluid = s["points"][s["kind"] == 0, :2]
    if not len(fluid):
        raise ValueError("%s: no fluid particles" % os.path.join(folder, name))
    print("t = %.2f s; the kernel reaches 2h = %.2f dp" % (t, reach_dp))
    print("current's depth (dp), first-row particles, their mean height above the bed (dp)")
    for low, high, count, height in first_row_by_depth(fluid, dp):
        print("%g-%g %d %.3f" % (low, high, count, height))


def measure(folder):
    """[(t, toe, body, film count, film reach, first row's height, model front)] over the run's snapshots after
    t = 0"""
    params = RunParams(folder)
    g, nu, x0, x1, depth, length = scene(params)
    dp = params.positive("numerics", "dp_m")
    rows = []
    for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd")):
        if t <= 0:
            continue
        s = vtp.read_vtp(os.path.join(folder, name), ("kind",), finite=True)
        fluid = s["points"][s["kind"] == 0, :2]
        if not len(fluid):
            raise ValueError("%s: no fluid particles" % os.path.join(folder, name))
        rows.append((t, *front_of(fluid, x0, dp)))
    if not rows:
        raise ValueError("%s: no snapshot after t = 0" % folder)
    rows.sort()  # the model is stepped forward through the snapshots' times
    fronts = lubrication_fronts(g, nu, x0, x1, depth, length, [r[0] for r in rows])
    return [r + (f,) for r, f in zip(rows, fronts)]


def times(text):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError("expected times in s separated by commas, got '%s'" % text)
    if not values or any(not (v > 0) or not np.isfinite(v) for v in values) or values != sorted(values):
        raise argparse.ArgumentTypeError("expected ascending times > 0 s, got '%s'" % text)
    return values


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("measure").add_argument("run_dir")
    rows = sub.add_parser("rows")
    rows.add_argument("run_dir")
    rows.add_argument("--time-s", type=cli_checks.non_negative, default=None,
                      help="the snapshot nearest this time, s (default the last)")
    ref = sub.add_parser("reference")
    ref.add_argument("case")
    ref.add_argument("--times-s", type=times, default=[1.0, 2.0, 5.0, 10.0, 20.0])
    args = parser.parse_args()
    try:
        if args.command == "reference":
            g, nu, x0, x1, depth, length = scene(RunParams(args.case))
            print("t (s), lubrication model's front (m), Huppert's similarity front (m)")
            for t, f in zip(args.times_s, lubrication_fronts(g, nu, x0, x1, depth, length, args.times_s)):
                print("%g %.4f %.4f" % (t, f, similarity_front(g, nu, (x1 - x0) * depth, t)))
            return 0
        if args.command == "rows":
            rows_command(args.run_dir, args.time_s)
            return 0
        rows = measure(args.run_dir)
    except (OSError, ValueError) as e:
        fail(str(e))
    print("t (s), toe (m), body (m), model (m), toe/model - 1, body/model - 1, film particles, film ahead (dp), "
          "first row's height (dp)")
    for t, toe, body, count, reach, height, model in rows:
        print("%.2f %.4f %.4f %.4f %+.4f %+.4f %d %.1f %.3f" % (t, toe, body, model, toe / model - 1,
                                                              body / model - 1, count, reach, height))
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
