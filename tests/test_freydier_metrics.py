#!/usr/bin/python3
"""Checks tools/freydier_metrics.py (and the writer in python/surgepy/vtp.py) on synthetic run folders.

Usage: test_freydier_metrics.py OUT_DIR [--keep]

Each synthetic run is an ID1 front (rho 1383, nu 0.0040491684743 m2/s, slope 15.3 deg,
u_b = 0.075 m/s, dp = 0.5 mm, upstream wall at x = 0.012 m, domain 0.6 m) written with
vtp.write_vtp/write_pvd every 0.1 s over 6 s: fluid particles on a lattice of spacing dp under the
exact lubrication profile, with velocities from the exact u* profile converted back to the
simulation frame (v_x = u_b u* - u_b), density 1383, plus wall particles (bottom belt, upstream
wall) and one stray fluid particle 30 dp downstream of the tip (it must not move the toe).
The number of particles in each lattice column is the rounded cumulative volume of the profile
from the wall (error diffusion), so the lattice carries the profile's volume to within half a
particle: rounding every column on its own would bias the depth by up to dp/2 (1.3 % of h_n here).

Checks (each metric printed against its bound):
  0. vtp.write_vtp -> read_vtp round-trips; the reference h_ref matches an independent solver.
  1. exact profile: zeta_f < 1e-3, zeta_h < 0.01, zeta_fs < 0.02, each zeta_u < 0.02; the CLI's
     --csv-row equals the module's numbers, --png writes a PNG.
  2. tip moving downstream at 0.02 u_b: zeta_f within 10 % of 0.02.
  3. depth x 1.05 everywhere: |zeta_h - 0.05| < 0.01, zeta_fs > 2x the exact case's and within
     0.01 of 0.05 RMS(h*_ref) over the same x* points.
  4. belt-frame velocities x 1.1: |zeta_u(9.7) - 0.1 sqrt(6/5)| < 0.02 (the exact RMS of
     0.1 u*_ref over zeta in [0, 1]: integral of (3z - 1.5z^2)^2 = 6/5).
  5. bad inputs exit 2 with a one-line message and no traceback.
Snapshot files of a finished case are deleted unless --keep is given (about 90 MB per case).
"""

import math
import os
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
TOOLS = os.path.join(HERE, "..", "tools")
import checks  # noqa: E402
from surgepy import vtp  # noqa: E402

SCRIPT = os.path.join(TOOLS, "freydier_metrics.py")
fm = checks.load_module(SCRIPT)

RHO = 1383.0
NU = 0.0040491684743
SLOPE_DEG = 15.3
BELT = -0.075
U_B = abs(BELT)
X_WALL = 0.012
DP = 0.0005
LENGTH = 0.6
G = 9.81
TAN = math.tan(math.radians(SLOPE_DEG))
H_N = math.sqrt(3 * NU * U_B / (G * math.sin(math.radians(SLOPE_DEG))))
X_TIP = 0.30  # 15.4 h_n from the wall: uniform zone x* in (9, 12.4)

PARAMS = """# synthetic ID1 front for tests/test_freydier_metrics.py
[domain]
length_m = {length}
height_m = 0.08
periodic_x = true

[fluid]
density_kgpm3 = {rho}
viscosity_m2ps = {nu}

[walls]
layers = 6
upstream = true
upstream_x_m = {x_wall}
bottom_speed_mps = {belt}

[body]
gravity_mps2 = {g}
slope_deg = {slope}

[numerics]
dp_m = {dp}
ch = 1.8
"""

def check(name, ok, text):
    """The shared ledger's check, always showing the measured value: the docs quote these numbers."""
    return checks.check(name, ok, text, show_detail=True)


# ------------------------------------------------------------------------------------------------
# Synthetic runs
# ------------------------------------------------------------------------------------------------

def h_ref_newton(xstar):
    """Independent solver of artanh(eta) - eta = x* tan(theta): Newton on a = artanh(eta),
    f(a) = a - tanh(a) - s, started from the tip asymptote / the far-field form."""
    s = xstar * TAN
    if s <= 0:
        return 0.0
    a = (3 * s) ** (1 / 3) if s < 1 else s + 1
    for _ in range(200):
        f = a - math.tanh(a) - s
        a_new = a - f / max(math.tanh(a) ** 2, 1e-300)
        a = max(a_new, 0.5 * a)
        if abs(f) < 1e-15 * max(1, s):
            break
    return math.tanh(a)


def params_text(**override):
    values = dict(length=LENGTH, rho=RHO, nu=NU, x_wall=X_WALL, belt=BELT, g=G, slope=SLOPE_DEG, dp=DP)
    values.update(override)
    return PARAMS.format(**values)


def write_params(run_dir, **override):
    with open(os.path.join(run_dir, "params.ini"), "w") as f:
        f.write(params_text(**override))


def snapshot(x_tip, depth_scale=1.0, u_scale=1.0):
    """Particles of one synthetic snapshot: (points (n, 2), velocity (n, 2), kind)."""
    ncol = int(math.ceil((x_tip - X_WALL) / DP)) + 2
    edges = X_WALL + DP * np.arange(ncol + 1)
    sub = 32  # column-mean height by the midpoint rule on 32 sub-cells
    xs = X_WALL + DP * (np.arange(ncol * sub) + 0.5) / sub
    h = depth_scale * H_N * fm.h_ref_star((x_tip - xs) / H_N, TAN)
    column_volume = h.reshape(ncol, sub).mean(axis=1) * DP
    cumulative = np.concatenate([[0.0], np.cumsum(column_volume)]) / DP ** 2
    counts = np.diff(np.floor(cumulative + 0.5)).astype(int)
    centres = 0.5 * (edges[:-1] + edges[1:])
    h_centre = depth_scale * H_N * fm.h_ref_star((x_tip - centres) / H_N, TAN)
    col = np.repeat(np.arange(ncol), counts)
    row = np.concatenate([np.arange(c) for c in counts]) if counts.sum() else np.zeros(0, int)
    x = centres[col]
    y = (row + 0.5) * DP
    zeta = y / np.maximum(h_centre[col], 1e-12)
    vx = U_B * u_scale * fm.u_ref_star(zeta) - U_B  # belt frame -> simulation frame
    # One stray fluid particle (a droplet) downstream of the tip.
    x = np.append(x, x_tip + 30 * DP)
    y = np.append(y, 0.5 * DP)
    vx = np.append(vx, BELT)
    nf = x.size
    # Walls: one layer of belt particles (kind 2, moving at the belt speed) and the upstream wall (kind 1).
    xb = (np.arange(int(LENGTH / DP)) + 0.5) * DP
    yw = (np.arange(int(0.06 / DP)) + 0.5) * DP
    pts = np.concatenate([np.column_stack([x, y]), np.column_stack([xb, np.full_like(xb, -0.5 * DP)]),
                          np.column_stack([np.full_like(yw, X_WALL - 0.5 * DP), yw])])
    vel = np.zeros((pts.shape[0], 2))
    vel[:nf, 0] = vx
    vel[nf:nf + xb.size, 0] = BELT
    kind = np.concatenate([np.zeros(nf), np.full(xb.size, 2), np.ones(yw.size)]).astype(np.uint8)
    return pts, vel, kind


def build_run(run_dir, tip_speed=0.0, depth_scale=1.0, u_scale=1.0, t_end=6.0, interval=0.1, x_tip=X_TIP):
    if os.path.isdir(run_dir):
        shutil.rmtree(run_dir)
    os.makedirs(run_dir)
    write_params(run_dir)
    entries = []
    n = int(round(t_end / interval))
    for k in range(n + 1):
        t = k * interval
        pts, vel, kind = snapshot(x_tip + tip_speed * (t - 0.5 * t_end), depth_scale, u_scale)
        name = "snap_%09d.vtp" % (100 * k)
        vtp.write_vtp(os.path.join(run_dir, name), pts,
                      {"velocity_mps": vel, "density_kgpm3": np.full(len(kind), RHO), "kind": kind},
                      t, 100 * k)
        entries.append((t, name))
    vtp.write_pvd(os.path.join(run_dir, "run.pvd"), entries)


def drop_snapshots(run_dir, keep):
    if not keep:
        for name in os.listdir(run_dir):
            if name.endswith(".vtp"):
                os.remove(os.path.join(run_dir, name))


def show(r):
    print("    zeta_f %.6f  zeta_h %.6f (top %.6f)  zeta_fs %.6f (top %.6f)  zeta_u %s  volume %.5f/%.5f"
          % (r["zeta_f"], r["zeta_h"], r["zeta_h_top"], r["zeta_fs"], r["zeta_fs_top"],
             " ".join("%g:%.5f" % (k, v) for k, v in r["zeta_u"].items()), r["volume_start"], r["volume_end"]))


def run_cli(*args):
    return subprocess.run([sys.executable, SCRIPT] + [str(a) for a in args], capture_output=True, text=True,
                          timeout=120)


# ------------------------------------------------------------------------------------------------
# Checks
# ------------------------------------------------------------------------------------------------

def check_vtp(out):
    print("0. vtp writer round trip and reference profile")
    rng = np.random.default_rng(1)
    n = 37
    pts = rng.normal(size=(n, 3)) * [1, 1e-3, 0]
    data = {"velocity_mps": rng.normal(size=(n, 3)) * [1, 1, 0], "density_kgpm3": 1000 + rng.normal(size=n),
            "pressure_pa": rng.normal(size=n) * 1e4, "kind": rng.integers(0, 3, n).astype(np.uint8),
            "id": rng.integers(-2**31, 2**31 - 1, n).astype(np.int32), "extra": rng.normal(size=(n, 2))}
    path = os.path.join(out, "roundtrip.vtp")
    vtp.write_vtp(path, pts, data, 12.345678901234567, 1234567890123)
    d = vtp.read_vtp(path)
    ok = (np.array_equal(d["points"], pts) and d["time_s"] == 12.345678901234567 and d["step"] == 1234567890123
          and d["velocity_mps"].dtype == np.float32 and d["kind"].dtype == np.uint8 and d["id"].dtype == np.int32
          and np.array_equal(d["extra"], data["extra"])
          and np.array_equal(d["verts_connectivity"], np.arange(n)) and np.array_equal(d["verts_offsets"], np.arange(1, n + 1)))
    for name in ("velocity_mps", "density_kgpm3", "pressure_pa", "kind", "id"):
        ok = ok and np.array_equal(d[name], np.asarray(data[name]).astype(d[name].dtype))
    check("read_vtp(write_vtp(...)) round-trips", ok, "%d points, 6 arrays, field data" % n)
    entries = [(0.0, "a.vtp"), (0.1, 'sub dir/a&b<c>".vtp'), (1 / 3, "c.vtp")]
    vtp.write_pvd(os.path.join(out, "roundtrip.pvd"), entries)
    check("read_pvd(write_pvd(...)) round-trips", vtp.read_pvd(os.path.join(out, "roundtrip.pvd")) == entries,
          "3 entries, escaped names")
    # The C writer's file (tests/test_vtk_output.c, the vtk_files fixture ctest runs first): same bytes.
    c_file = os.path.join(out, "..", "vtk", "synthetic.vtp")
    same = False
    if os.path.isfile(c_file):
        d = vtp.read_vtp(c_file)
        vtp.write_vtp(os.path.join(out, "c_copy.vtp"), d["points"],
                      {k: d[k] for k in ("velocity_mps", "density_kgpm3", "pressure_pa", "kind", "id")},
                      d["time_s"], d["step"])
        with open(c_file, "rb") as a, open(os.path.join(out, "c_copy.vtp"), "rb") as b:
            same = a.read() == b.read()
    check("write_vtp == C surge_vtp_write, byte for byte", same,
          c_file if os.path.isfile(c_file) else "%s is not there (ctest runs vtk_output first)" % c_file)
    xstar = np.array([1e-4, 0.01, 0.1, 0.76, 1.5, 5.0, 9.7, 20.0, 80.0])
    ours = fm.h_ref_star(xstar, TAN)
    theirs = np.array([h_ref_newton(v) for v in xstar])
    err = float(np.max(np.abs(ours - theirs)))
    check("h_ref_star vs an independent Newton solver", err < 1e-9, "max |diff| %.2e < 1e-9" % err)
    tip = float(fm.h_ref_star(1e-6, TAN)) / (3 * 1e-6 * TAN) ** (1 / 3)
    check("tip asymptote h* -> (3 x* tan theta)^(1/3)", abs(tip - 1) < 1e-3, "ratio %.6f" % tip)
    print("  h_n = %.5f mm = %.2f dp" % (1e3 * H_N, H_N / DP))


def check_exact(out, keep):
    print("1. exact lubrication front (tip fixed at x = %.3f m)" % X_TIP)
    run_dir = os.path.join(out, "exact")
    build_run(run_dir)
    r = fm.compute(run_dir)
    show(r)
    check("zeta_f < 1e-3", r["zeta_f"] < 1e-3, "%.2e" % r["zeta_f"])
    check("zeta_h < 0.01", r["zeta_h"] < 0.01, "%.5f" % r["zeta_h"])
    check("zeta_fs < 0.02", r["zeta_fs"] < 0.02, "%.5f" % r["zeta_fs"])
    for xs, v in r["zeta_u"].items():
        check("zeta_u(%g) < 0.02" % xs, v < 0.02, "%.5f" % v)
    toe_err = abs(np.mean(r["toes"]) - X_TIP) / H_N
    check("toe on the tip (|x_toe - x_tip| < 0.05 h_n)", toe_err < 0.05, "%.4f h_n" % toe_err)
    check("fluid volume constant", abs(r["volume_start"] - 1) < 1e-9 and abs(r["volume_end"] - 1) < 1e-9,
          "%.6f, %.6f" % (r["volume_start"], r["volume_end"]))
    png = os.path.join(out, "exact.png")
    if os.path.exists(png):
        os.remove(png)
    p = run_cli(run_dir, "--csv-row", "--png", png)
    expected = fm.csv_row(r)
    check("CLI --csv-row = module values", p.returncode == 0 and p.stdout.strip() == expected,
          "rc %d, %r" % (p.returncode, p.stdout.strip()))
    ok_png = os.path.isfile(png) and open(png, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    check("CLI --png writes a PNG", ok_png, png)
    p = run_cli(run_dir, "--window-s", "2", "--end-s", "5")
    check("CLI summary (--window-s 2 --end-s 5)", p.returncode == 0 and "zeta_fs" in p.stdout and "[3, 5] s" in p.stdout,
          "rc %d, %d lines" % (p.returncode, len(p.stdout.splitlines())))
    with open(os.path.join(out, "exact_summary.txt"), "w") as f:
        f.write(p.stdout)
    drop_snapshots(run_dir, keep)
    return r


def check_moving(out, keep):
    print("2. tip moving downstream at 0.02 u_b")
    run_dir = os.path.join(out, "moving")
    build_run(run_dir, tip_speed=0.02 * U_B)
    r = fm.compute(run_dir)
    show(r)
    check("zeta_f within 10 % of 0.02", abs(r["zeta_f"] - 0.02) < 0.002,
          "%.5f (sub-window speeds %s mm/s)" % (r["zeta_f"], " ".join("%.3f" % (1e3 * s[2]) for s in r["toe_subwindows"])))
    drop_snapshots(run_dir, keep)


def check_deeper(out, keep, exact):
    print("3. depth x 1.05 everywhere")
    run_dir = os.path.join(out, "deeper")
    build_run(run_dir, depth_scale=1.05)
    r = fm.compute(run_dir)
    show(r)
    check("|zeta_h - 0.05| < 0.01", abs(r["zeta_h"] - 0.05) < 0.01, "%.5f" % r["zeta_h"])
    prof = r["profile"]
    sel = (prof["xstar"] > 0) & (prof["xstar"] <= fm.FREE_SURFACE_XSTAR + 1e-9)
    expected = 0.05 * float(np.sqrt(np.mean(prof["h_ref"][sel] ** 2)))
    check("zeta_fs > 2 x exact case's (%.4f)" % exact["zeta_fs"], r["zeta_fs"] > 2 * exact["zeta_fs"],
          "%.5f" % r["zeta_fs"])
    check("|zeta_fs - 0.05 RMS(h*_ref)| < 0.01", abs(r["zeta_fs"] - expected) < 0.01,
          "%.5f vs %.5f" % (r["zeta_fs"], expected))
    drop_snapshots(run_dir, keep)


def check_faster(out, keep):
    print("4. belt-frame velocities x 1.1")
    run_dir = os.path.join(out, "faster")
    build_run(run_dir, u_scale=1.1)
    r = fm.compute(run_dir)
    show(r)
    expected = 0.1 * math.sqrt(6.0 / 5.0)  # RMS over zeta in [0, 1] of 0.1 (3 zeta - 1.5 zeta^2)
    check("|zeta_u(9.7) - 0.1 sqrt(6/5)| < 0.02", abs(r["zeta_u"][9.7] - expected) < 0.02,
          "%.5f vs %.5f" % (r["zeta_u"][9.7], expected))
    drop_snapshots(run_dir, keep)


def check_bad_inputs(out, keep):
    print("5. bad inputs: exit 2, one line, no traceback")
    base = os.path.join(out, "bad")
    if os.path.isdir(base):
        shutil.rmtree(base)
    os.makedirs(base)
    mini = os.path.join(base, "mini")  # 1 s of snapshots, every 0.1 s
    build_run(mini, t_end=1.0)

    def variant(name, params=None, pvd=True, files=None, **override):
        d = os.path.join(base, name)
        os.makedirs(d)
        if params is None:
            write_params(d, **override)
        else:
            with open(os.path.join(d, "params.ini"), "w") as f:
                f.write(params)
        if pvd:
            vtp.write_pvd(os.path.join(d, "run.pvd"),
                          files or [(t, os.path.join("..", "mini", f)) for t, f in vtp.read_pvd(os.path.join(mini, "run.pvd"))])
        return d

    no_visc = "\n".join(line for line in params_text().splitlines() if "viscosity" not in line)
    sparse = os.path.join(base, "sparse")
    build_run(sparse, t_end=6.0, interval=1.0)
    short = os.path.join(base, "short")
    build_run(short, t_end=1.0, x_tip=X_WALL + 10 * H_N)
    corrupt = variant("corrupt", files=[(0.0, "../mini/snap_000000000.vtp"), (0.1, "broken.vtp")])
    with open(os.path.join(corrupt, "broken.vtp"), "w") as f:
        f.write("<?xml version='1.0'?><VTKFile type='PolyData'>")
    cases = [
        ("missing folder", [os.path.join(base, "nowhere")], "no such run folder"),
        ("no run.pvd", [variant("nopvd", pvd=False)], "run.pvd"),
        ("no params.ini", [base], "params.ini"),
        ("empty window", [mini, "--end-s", "0.05", "--window-s", "0.01"], "window"),
        ("--end-s outside the run", [mini, "--end-s", "9"], "outside"),
        ("--window-s 0", [mini, "--window-s", "0"], "window"),
        ("missing params key", [variant("novisc", params=no_visc)], "viscosity_m2ps"),
        ("non-numeric params value", [variant("badslope", slope="steep")], "slope_deg"),
        ("belt speed 0", [variant("nobelt", belt=0.0)], "bottom_speed_mps"),
        ("snapshot listed but missing", [variant("lost", files=[(0.0, "gone.vtp"), (0.1, "gone2.vtp")])], "gone"),
        ("corrupt snapshot", [corrupt, "--window-s", "1"], "broken.vtp"),
        ("1 snapshot per second", [sparse], "per second"),
        ("domain too short", [short, "--window-s", "1"], "too short"),
        ("bad option value", [mini, "--window-s", "abc"], "window-s"),
    ]
    for name, args, word in cases:
        p = run_cli(*args)
        err = p.stderr.strip()
        ok = (p.returncode == 2 and err.count("\n") == 0 and "Traceback" not in err and word in err
              and p.stdout == "")
        check(name, ok, "rc %d: %s" % (p.returncode, err if len(err) < 150 else err[:150] + "..."))
    for run_dir in (mini, sparse, short):
        drop_snapshots(run_dir, keep)


def main():
    args = [a for a in sys.argv[1:] if a != "--keep"]
    keep = "--keep" in sys.argv[1:]
    if len(args) != 1:
        print("usage: test_freydier_metrics.py OUT_DIR [--keep]", file=sys.stderr)
        return 2
    out = args[0]
    os.makedirs(out, exist_ok=True)
    start = time.time()
    print("freydier_metrics synthetic checks in %s" % out)
    check_vtp(out)
    exact = check_exact(out, keep)
    check_moving(out, keep)
    check_deeper(out, keep, exact)
    check_faster(out, keep)
    check_bad_inputs(out, keep)
    print("%.1f s" % (time.time() - start))
    return checks.finish()


if __name__ == "__main__":
    sys.exit(main())
