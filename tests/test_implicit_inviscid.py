#!/usr/bin/python3
"""The implicit scheme without viscosity (fluid.viscosity_m2ps = 0): the still tank tilted by 10 degrees must slosh
as it does at nu = 1e-6 m^2/s, where the viscous solve changes v* by less than its tolerance. Until 2026-11-27 an
inviscid step skipped the viscous solve and kept v* = v_n, dropping gravity and the pressure gradient: the fluid
never moved (kinetic energy 0 at 0.2 s against 0.816 J/m at nu = 1e-6, the mean speed along x 0 against 0.0995
m/s). Usage: test_implicit_inviscid.py SURGE ROOT OUTDIR"""
import csv
import os
import subprocess
import sys

surge, root, out = sys.argv[1:4]
END_S = 0.2
TOLERANCE = 0.01  # relative: measured 2026-11-27: 1.2e-4 (kinetic energy) and 3e-6 (mean vx) apart


def last_row(viscosity):
    folder = os.path.join(out, "nu_%g" % viscosity)
    cmd = [surge, "run", os.path.join(root, "cases", "still_tank.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.scheme=implicit", "-s", "fluid.viscosity_m2ps=%g" % viscosity, "-s", "body.slope_deg=10",
           "-s", "time.end_s=%g" % END_S, "-s", "output.progress_interval_s=0", "--threads", "1"]
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        sys.exit("nu %g: the run failed\n%s\n%s" % (viscosity, " ".join(cmd), run.stderr[-1500:]))
    with open(os.path.join(folder, "diagnostics.csv")) as f:
        return list(csv.DictReader(f))[-1]


inviscid, water = last_row(0.0), last_row(1e-6)
failures = 0
for column in ("kinetic_energy_jpm", "mean_vx_mps"):
    a, b = float(inviscid[column]), float(water[column])
    ok = abs(b) > 0 and abs(a - b) <= TOLERANCE * abs(b)
    print("%s at %s s: nu 0 %.6g, nu 1e-6 %.6g, %.2g apart (bound %g) %s"
          % (column, inviscid["time_s"], a, b, abs(a - b) / abs(b) if b else float("inf"), TOLERANCE,
             "ok" if ok else "FAILED"))
    failures += not ok
sys.exit(1 if failures else 0)
