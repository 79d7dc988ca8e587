#!/usr/bin/python3
"""Quadratic no-slip walls (walls.quadratic_no_slip, docs/method.md): with them the implicit scheme carries the
flux of a channel or film only a few particles across. Plane Poiseuille flow (cases/poiseuille.ini, gap 1 mm) with
2, 3 and 8 particles across the gap, run to its steady state: the particles' mean velocity within 3 % of the exact
parabola's at their heights (measured +0.8, +1.6 and +1.5 %; mDBC's mirror +154, +78 and +11 %). A film down the
incline (cases/incline_film.ini) 4 particles deep: within 8 % of the Nusselt film's (measured +6.5 %; the mirror
+13.9 %), and closer than the mirror's. The explicit scheme refuses the option with a message.

usage: test_quadratic_no_slip.py SURGE SOURCE_DIR WORK_DIR"""
import math
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402
from surgepy import vtp  # noqa: E402

surge, source, work = sys.argv[1:4]


def run(case, name, *settings):
    out = os.path.join(work, name)
    args = [surge, "run", os.path.join(source, "cases", case), "-o", out, "--overwrite", "-s", "numerics.scheme=implicit",
            "-s", "output.progress_interval_s=0", "--threads", "1"]
    for s in settings:
        args += ["-s", s]
    r = subprocess.run(args, capture_output=True, text=True, timeout=600, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    if not check("%s runs" % name, r.returncode == 0, (r.stdout + r.stderr)[-600:]):
        return None
    _, last = vtp.read_pvd(os.path.join(out, "run.pvd"))[-1]
    d = vtp.read_vtp(os.path.join(out, last), ("kind", "velocity_mps"))
    fluid = d["kind"] == 0
    return d["points"][fluid, 1], d["velocity_mps"][fluid, 0]


def mean_ratio(result, exact):
    y, u = result
    return u.mean() / exact(y).mean()


GAP_M, FORCE, NU = 0.001, 2e-4, 1e-6  # cases/poiseuille.ini


def poiseuille(y):
    return FORCE / (2 * NU) * y * (GAP_M - y)


for across in (2, 3, 8):
    dp = GAP_M / across
    length = 8 * GAP_M  # three kernel supports at 2 across
    results = {}
    for quadratic in (0, 1):
        results[quadratic] = run("poiseuille.ini", "poiseuille_%d_q%d" % (across, quadratic), "numerics.dp_m=%r" % dp,
                                 "domain.length_m=%r" % length, "fluid.x1_m=%r" % length, "time.end_s=2",
                                 "output.snapshot_interval_s=0.5", "walls.quadratic_no_slip=%d" % quadratic)
    if results[0] is not None and results[1] is not None:
        mirror, fitted = mean_ratio(results[0], poiseuille), mean_ratio(results[1], poiseuille)
        check("Poiseuille %d particles across: the quadratic walls' mean velocity within 3 %% of the exact" % across,
              abs(fitted - 1) <= 0.03, "%+.4f (the mirror's %+.4f)" % (fitted - 1, mirror - 1), show_detail=True)

G, SLOPE, FILM_NU, DEPTH = 9.81, math.radians(10), 0.05, 0.25  # cases/incline_film.ini


def nusselt(y):
    return G * math.sin(SLOPE) * (2 * DEPTH * y - y * y) / (2 * FILM_NU)


films = [run("incline_film.ini", "film_q%d" % q, "numerics.dp_m=0.0625", "numerics.ch=1.8", "walls.layers=0",
             "time.end_s=4", "output.snapshot_interval_s=1", "walls.quadratic_no_slip=%d" % q) for q in (0, 1)]
if films[0] is not None and films[1] is not None:
    mirror, fitted = mean_ratio(films[0], nusselt), mean_ratio(films[1], nusselt)
    check("a film 4 particles deep: the quadratic walls' mean velocity within 8 % of the Nusselt film's",
          abs(fitted - 1) <= 0.08, "%+.4f" % (fitted - 1), show_detail=True)
    check("a film 4 particles deep: the quadratic walls closer to the Nusselt film than the mirror",
          abs(fitted - 1) < abs(mirror - 1), "%+.4f against %+.4f" % (fitted - 1, mirror - 1), show_detail=True)
r = subprocess.run([surge, "check", os.path.join(source, "cases", "poiseuille.ini"), "-s", "walls.quadratic_no_slip=true"],
                   capture_output=True, text=True, timeout=60)
check("the explicit scheme refuses walls.quadratic_no_slip, naming it and the scheme",
      r.returncode == 2 and "walls.quadratic_no_slip" in r.stderr and "numerics.scheme = implicit" in r.stderr,
      r.stderr.strip())
sys.exit(finish())
