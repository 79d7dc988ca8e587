#!/usr/bin/python3
"""The implicit scheme carries a Freydier front: ID1 at dp = 1 mm, C_h 1.3, from the lubrication
profile, 2.5 s of flow. Without the kernel-sum free-surface test (implicit.surface_kernel_margin = 1 turns it off)
this run stopped at 1.77 s on the density check at the front's foot; with it the same front ran 10.2 s,
and with the compressed particles' shift (implicit.anti_clumping) as well, 40 s (docs/validation/stability.md).

Then the front at dp = 2 mm (9 particles in h_n), C_h 1.8, the Freydier cases' settings, 8 s from the lubrication
profile, against the paper's converged values (tools/freydier_metrics.py over the last 3 s): the four targets,
zeta_f < 1 % excepted, which this resolution misses (3 % here; measured: zeta_h 0.029, zeta_f 0.009, zeta_fs 0.046,
zeta_u 0.031 / 0.023 / 0.011).

Usage: test_implicit_front.py SURGE_BINARY SOURCE_DIR WORK_DIR
Checks: the run ends healthy at 2.5 s; the fluid's volume stays within 0.1 % of the first row's; the fastest fluid
moves between 0.05 and 0.2 m/s (the belt moves at 0.075 m/s: the front flows, nothing jets); the
dp = 2 mm run's zeta_h < 0.05, zeta_f < 0.03, zeta_fs < 0.10, zeta_u < 0.05 at each station.
Each check prints "name: ok" or "name: FAILED ..."; the script exits 1 if any failed.
"""
import csv
import os
import shutil
import subprocess
import sys

SURGE, SOURCE, WORK = sys.argv[1:4]
from checks import check, finish, load_module  # noqa: E402
freydier_metrics = load_module(os.path.join(SOURCE, "tools", "freydier_metrics.py"))

shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
run = subprocess.run([SURGE, "run", os.path.join(SOURCE, "cases", "freydier_id1.ini"), "-o", WORK, "--overwrite",
                      "-s", "numerics.scheme=implicit", "-s", "numerics.ch=1.3", "-s", "fluid.shape=lubrication",
                      "-s", "time.end_s=2.5", "-s", "output.snapshot_interval_s=2.5", "--threads", "1"],
                     capture_output=True, text=True, timeout=900,
                     env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
rows = []
if os.path.isfile(os.path.join(WORK, "diagnostics.csv")):
    with open(os.path.join(WORK, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
end_s = float(rows[-1]["time_s"]) if rows else float("nan")
check("implicit Freydier front, C_h 1.3: healthy to 2.5 s (ended at %.3f s)" % end_s,
      run.returncode == 0 and end_s > 2.49, run.stderr[-1500:])
if rows:
    volume = [float(r["fluid_volume_m2"]) for r in rows]
    drift = max(abs(v / volume[0] - 1) for v in volume)
    check("fluid volume within 0.1 %% of the first row's (largest change %.2e)" % drift, drift < 1e-3)
    # the front flows (its surface runs at about 0.1 m/s against the belt's 0.075 m/s) and nothing jets: a fluid at
    # rest fails the first bound, a mode that grows the second (the density is the health monitor's to bound)
    speed = max(float(r["max_speed_mps"]) for r in rows[1:])
    check("fastest fluid between 0.05 and 0.2 m/s (%.4f m/s)" % speed, 0.05 < speed < 0.2)

coarse = os.path.join(WORK, "dp2mm")
run = subprocess.run([SURGE, "run", os.path.join(SOURCE, "cases", "freydier_id1.ini"), "-o", coarse, "--overwrite",
                      "-s", "numerics.scheme=implicit", "-s", "numerics.dp_m=0.002", "-s", "numerics.ch=1.8",
                      "-s", "walls.layers=0", "-s", "fluid.shape=lubrication", "-s", "time.end_s=8",
                      "-s", "output.progress_interval_s=0", "--threads", "1"],
                     capture_output=True, text=True, timeout=900, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
check("implicit Freydier front, dp 2 mm, C_h 1.8: healthy to 8 s", run.returncode == 0, run.stderr[-1500:])
if run.returncode == 0:
    m = freydier_metrics.compute(coarse, window_s=3.0)
    for key, bound in (("zeta_h", 0.05), ("zeta_f", 0.03), ("zeta_fs", 0.10)):
        check("%s over 5-8 s below %g (%.4f)" % (key, bound, m[key]), m[key] < bound)
    for station, value in sorted(m["zeta_u"].items()):
        check("zeta_u at x* = %g below 0.05 (%.4f)" % (station, value), value < 0.05)
sys.exit(finish())
