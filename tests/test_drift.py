#!/usr/bin/python3
"""Long-run consistency and thin layers on walls (issue #22; docs/validation/drift.md).

  test_drift.py SURGE SOURCE_DIR OUT_DIR GROUP

GROUP
  conservation  the coarse debris surge (cases/debris_surge.ini, dp = 0.1 m) for 6 s with
                shifting.consistent_density = true: kernel sum / density in the surge body stays within 1 % of 1
                at every snapshot (without it the same run reads 0.983 at 6 s, 0.967 at 8 s, 0.844 at 20 s), and
                the fluid volume within 0.1 %
  thin_layers   a viscous gravity current 10 particles across (ends about one particle deep) for 8 s, and a film
                3 particles deep down an incline for 10 s: no fluid particle below the bed face (y < 0) in any
                snapshot, and the health monitor stays quiet (before walls.no_penetration the current lost a
                particle through the bed at 3.19 s)
"""
import glob
import os
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

SURGE, SOURCE, OUT, GROUP = sys.argv[1:5]
sys.path.insert(0, os.path.join(SOURCE, "tools"))
import vtp  # noqa: E402

GRAVITY_CURRENT = """# planar viscous gravity current released against the left wall (docs/validation/drift.md)
[domain]
length_m = 0.8
height_m = 0.15
periodic_x = false
[fluid]
density_kgpm3 = 1000
viscosity_m2ps = 0.01
x0_m = 0
x1_m = 0.1
depth_m = 0.1
[walls]
bottom = true
left = true
right = true
upstream = false
bottom_speed_mps = 0
[body]
gravity_mps2 = 9.81
slope_deg = 0
[numerics]
dp_m = 0.01
[time]
end_s = 8
[output]
snapshot_interval_s = 0.5
"""


def run(name, case, *overrides):
    """Runs SURGE on case into OUT/name; returns (exit status, output)."""
    out = os.path.join(OUT, name)
    cmd = [SURGE, "run", case, "-o", out, "--threads", "2"]
    for o in overrides:
        cmd += ["-s", o]
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=1200)
    return proc.returncode, proc.stdout, out


def lowest_fluid(run_dir):
    """(lowest fluid y over all snapshots, the time it was seen)."""
    lowest = (float("inf"), 0.0)
    for path in sorted(glob.glob(os.path.join(run_dir, "snap_*.vtp"))):
        s = vtp.read_vtp(path, ("time_s", "kind"))
        y = s["points"][s["kind"] == 0, 1]
        if y.size and y.min() < lowest[0]:
            lowest = (float(y.min()), s["time_s"])
    return lowest


def conservation():
    status, output, run_dir = run("debris_surge_consistent", os.path.join(SOURCE, "cases", "debris_surge.ini"),
                                  "time.end_s=6", "output.snapshot_interval_s=1",
                                  "shifting.consistent_density=true")
    if not check("debris surge runs 6 s", status == 0, output[-2000:]):
        return
    proc = subprocess.run([sys.executable, os.path.join(SOURCE, "tools", "surge_drift.py"), run_dir, "--every", "1",
                           "--csv", os.path.join(run_dir, "drift.csv")], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
    if not check("surge_drift reads the run", proc.returncode == 0, proc.stdout):
        return
    with open(os.path.join(run_dir, "drift.csv")) as f:
        header = f.readline().strip().split(",")
        rows = [dict(zip(header, map(float, line.split(",")))) for line in f if line.strip()]
    worst = min(r["kernel_sum_over_density"] for r in rows)
    check("kernel sum / density in the body within 1 % of 1 at every snapshot", abs(worst - 1) < 0.01,
          proc.stdout, show_detail=True)
    with open(os.path.join(run_dir, "diagnostics.csv")) as f:
        header = f.readline().strip().split(",")
        volumes = [float(line.split(",")[header.index("fluid_volume_m2")]) for line in f if line.strip()]
    check("fluid volume sum m/rho within 0.1 % of the initial", abs(volumes[-1] / volumes[0] - 1) < 1e-3,
          "%.6f -> %.6f m2" % (volumes[0], volumes[-1]), show_detail=True)


def thin_layers():
    case = os.path.join(OUT, "gravity_current.ini")
    with open(case, "w") as f:
        f.write(GRAVITY_CURRENT)
    status, output, run_dir = run("gravity_current_10", case)
    check("gravity current (10 across) runs 8 s with the health monitor quiet", status == 0, output[-2000:])
    y, t = lowest_fluid(run_dir)
    check("gravity current: no fluid below the bed face", y >= 0, "lowest %.5f m at t = %.2f s" % (y, t),
          show_detail=True)
    status, output, run_dir = run("film_3_deep", os.path.join(SOURCE, "cases", "incline_film.ini"),
                                  "numerics.dp_m=0.01", "fluid.depth_m=0.03", "domain.length_m=0.5",
                                  "fluid.x1_m=0.5", "numerics.ch=1.8", "walls.layers=0", "numerics.c0_mps=0",
                                  "time.end_s=10", "output.snapshot_interval_s=1")
    check("film 3 particles deep runs 10 s with the health monitor quiet", status == 0, output[-2000:])
    y, t = lowest_fluid(run_dir)
    check("film 3 deep: no fluid below the bed face", y >= 0, "lowest %.5f m at t = %.2f s" % (y, t),
          show_detail=True)


groups = {"conservation": conservation, "thin_layers": thin_layers}
if GROUP not in groups:
    sys.exit("test_drift.py: unknown group '%s' (%s)" % (GROUP, ", ".join(groups)))
os.makedirs(OUT, exist_ok=True)
groups[GROUP]()
sys.exit(finish())
