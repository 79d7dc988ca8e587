#!/usr/bin/python3
"""Where the methods fail: short runs of a belt-front case over shifting form x C_h x CFL x c0 factor, recording
for each cell whether the health monitor let it finish, the failing check (particle, step, time) when it did
not, and for every cell a frame of the particles near the upstream wall and the front.

  studies/stability/stability_map.py run [--case id1] [--dp 0.002] [--shifting none,velocity,lind] [--ch 1.3,1.8]
        [--cfl 0.2,0.5] [--c0-factor 10,5] [--end-s 3] [--threads 2]
        [--runs-dir runs/stability] [--csv studies/stability/data/stability_map.csv] [--frames docs/validation/stability]
  studies/stability/stability_map.py implicit-run [--steps-ms 1,2,3,5,0] [--end-s 10] [--threads 1]
        [--runs-dir runs/stability] [--implicit-csv studies/stability/data/implicit_still_tank.csv]
  studies/stability/stability_map.py chart [--csv ...] [--implicit-csv ...] [--png docs/validation/stability_map.png]

implicit-run: the implicit scheme's still tank (cases/still_tank.ini) at fixed steps (0: the scheme's own), with the
defaults and with the kernels cut off under the surface (implicit.surface_images=0, pressure_relaxation=0): status
and the kinetic energy at 1 s, 5 s and the end. "At rest" is a kinetic energy at the end within 10 times that of the
defaults at the scheme's own step. The chart draws these beside the explicit scheme's cells.

One CSV row per cell (appended; cells already in the CSV are skipped): the parameters, status (healthy or the
check that failed), the health message, wall time, the final time reached, the largest density deviation and
the mean x velocity of the fluid over the last second (the drift of its centre of mass).
"""
import argparse
import os
import re
import subprocess
import sys
import time

from surgepy import cli_checks, study, vtp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

IMPLICIT_COLUMNS = ["variant", "dt_ms", "end_s", "status", "message", "wall_s", "time_reached_s", "ke_1s_jpm",
                    "ke_5s_jpm", "ke_end_jpm"]
IMPLICIT_VARIANTS = {"defaults": [], "cut-off": ["-s", "implicit.surface_images=0", "-s", "implicit.pressure_relaxation=0"]}

COLUMNS = ["case", "dp_m", "shifting", "ch", "cfl", "c0_factor", "end_s", "status", "message", "wall_s",
           "time_reached_s", "max_density_deviation", "mean_vx_last_s_mps", "frame"]


def non_negative_numbers(text):
    """Comma-separated steps in ms, 0 for the scheme's own."""
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if not values or any(not (v >= 0 and v < 1e6) for v in values):
        fail("--steps-ms: expected comma-separated steps in ms, 0 for the scheme's own, got '%s'" % text)
    return values


def fail(message):
    study.fail("stability_map", message)


def cell_name(args, shifting, ch, cfl, c0f):
    return "%s_dp%g_%s_ch%g_cfl%g_c0x%g" % (args.case, args.dp, shifting, ch, cfl, c0f)


def diagnostics_summary(folder):
    """Time reached, largest density deviation, mean fluid x velocity over the last second."""
    rows = study.read_rows("stability_map", os.path.join(folder, "diagnostics.csv"), dict(
        time_s=float, max_density_deviation=float, mean_vx_mps=float))
    t = [float(r["time_s"]) for r in rows]
    last = [float(r["mean_vx_mps"]) for r, ti in zip(rows, t) if ti >= t[-1] - 1.0]
    return t[-1], max(float(r["max_density_deviation"]) for r in rows), sum(last) / len(last)


def draw_frame(folder, png, title):
    """Particles of the last good state (or the final snapshot), coloured by speed, near the wall and front."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    path = os.path.join(folder, "last_good.vtp")
    try:
        if not os.path.isfile(path):
            entries = vtp.read_pvd(os.path.join(folder, "run.pvd"))
            if not entries:
                fail("%s: lists no snapshots" % os.path.join(folder, "run.pvd"))
            path = os.path.join(folder, entries[-1][1])
        s = vtp.read_vtp(path, ("time_s", "velocity_mps", "kind"))
    except vtp.VtpError as e:
        fail(str(e))
    x, y = s["points"][:, 0], s["points"][:, 1]
    speed = np.hypot(s["velocity_mps"][:, 0], s["velocity_mps"][:, 1])
    fluid = s["kind"] == 0
    if not fluid.any():
        fail("%s: no fluid particles" % path)
    fig, ax = plt.subplots(figsize=(11, 2.8))
    ax.scatter(x[~fluid], y[~fluid], s=1.5, c="0.6")
    sc = ax.scatter(x[fluid], y[fluid], s=2.5, c=speed[fluid], cmap="viridis")
    fig.colorbar(sc, ax=ax, label="speed (m/s)")
    ax.set_xlim(0, max(0.05, x[fluid].max() + 0.02))
    ax.set_ylim(-0.01, max(0.03, y[fluid].max() + 0.005))
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, along the belt)")
    ax.set_ylabel("y (m)")
    ax.set_title("%s, t = %.3f s (%s)" % (title, s["time_s"], os.path.basename(path)), fontsize=9)
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    plt.close(fig)


def run_cell(args, shifting, ch, cfl, c0f):
    name = cell_name(args, shifting, ch, cfl, c0f)
    folder = os.path.join(args.runs_dir, name)
    argv = [args.surge, "run", os.path.join(ROOT, "cases", "freydier_%s.ini" % args.case),
            "-s", "numerics.dp_m=%g" % args.dp, "-s", "numerics.ch=%g" % ch, "-s", "walls.layers=0",
            "-s", "numerics.cfl=%g" % cfl, "-s", "numerics.c0_factor=%g" % c0f, "-s", "shifting.form=%s" % shifting,
            "-s", "time.end_s=%g" % args.end_s, "-s", "output.snapshot_interval_s=0.5",
            "-s", "output.progress_interval_s=0", "--threads", str(args.threads), "-o", folder,
            "--overwrite"]
    start = time.time()
    r = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, errors="replace",
                       env=study.solver_environment())
    wall = time.time() - start
    status, message = run_outcome(name, folder, r)
    t_reached, max_dev, mean_vx = diagnostics_summary(folder)
    os.makedirs(args.frames, exist_ok=True)
    frame = os.path.join(args.frames, name + ".png")
    draw_frame(folder, frame, "%s: %s" % (name, status))
    return {"case": args.case, "dp_m": args.dp, "shifting": shifting, "ch": ch, "cfl": cfl, "c0_factor": c0f,
            "end_s": args.end_s, "status": status, "message": message,
            "wall_s": "%.1f" % wall, "time_reached_s": "%.4f" % t_reached, "max_density_deviation": "%.5f" % max_dev,
            "mean_vx_last_s_mps": "%.6f" % mean_vx, "frame": os.path.relpath(frame, os.path.dirname(args.csv))}


def command_run(args):
    done = {(r["case"], float(r["dp_m"]), r["shifting"], float(r["ch"]), float(r["cfl"]), float(r["c0_factor"]),
             float(r["end_s"])) for r in study.existing_rows("stability_map", args.csv, COLUMNS, dict(
                 case=str, dp_m=float, shifting=str, ch=float, cfl=float, c0_factor=float, end_s=float))}
    for shifting in args.shifting:
        for ch in args.ch:
            for cfl in args.cfl:
                for c0f in args.c0_factor:
                    if (args.case, args.dp, shifting, ch, cfl, c0f, args.end_s) in done:
                        continue
                    row = run_cell(args, shifting, ch, cfl, c0f)
                    study.append_row(args.csv, COLUMNS, row)
                    print("stability_map: %s: %s (%s s)" % (cell_name(args, shifting, ch, cfl, c0f), row["status"],
                                                           row["wall_s"]), flush=True)
    return 0


def run_outcome(name, folder, r):
    """(status, message) of a finished surge run: healthy, the health check that stopped it, or the exit code."""
    study.stop_on_surge_error("stability_map: " + name, folder, r.returncode, r.stderr)
    if r.returncode == 0:
        return "healthy", ""
    if r.returncode == 1:
        message = next((l for l in r.stderr.splitlines() if "health check failed" in l), r.stderr.strip())
        m = re.search(r"health check failed: (.*?) at ", message)
        return "failed: " + (m.group(1) if m else "health monitor"), message.replace("surge: ", "")
    return "error: exit %d" % r.returncode, r.stderr.strip().splitlines()[-1] if r.stderr.strip() else ""


def kinetic_energy_at(folder, times):
    """The kinetic energy (J/m) of diagnostics.csv's row nearest each time (nan past the run's end) and the last
    time reached."""
    rows = [{k: float(r[k]) for k in ("time_s", "kinetic_energy_jpm")} for r in study.read_rows(
        "stability_map", os.path.join(folder, "diagnostics.csv"), dict(time_s=float, kinetic_energy_jpm=float))]
    end = rows[-1]["time_s"] if rows else 0.0
    values = []
    for t in times:
        near = min(rows, key=lambda r: abs(r["time_s"] - t)) if rows else None
        values.append(near["kinetic_energy_jpm"] if near and t <= end + 0.05 else float("nan"))
    return values, end


def command_implicit_run(args):
    done = {(r["variant"], float(r["dt_ms"]), float(r["end_s"])) for r in study.existing_rows(
        "stability_map", args.implicit_csv, IMPLICIT_COLUMNS, dict(variant=str, dt_ms=float, end_s=float))}
    for variant, extra in IMPLICIT_VARIANTS.items():
        for dt_ms in args.steps_ms:
            if (variant, dt_ms, args.end_s) in done:
                continue
            name = "still_tank_implicit_%s_dt%gms" % (variant, dt_ms)
            folder = os.path.join(args.runs_dir, name)
            argv = [args.surge, "run", os.path.join(ROOT, "cases", "still_tank.ini"), "-s", "numerics.scheme=implicit",
                    "-s", "numerics.dt_fixed_s=%g" % (dt_ms / 1000), "-s", "time.end_s=%g" % args.end_s,
                    "-s", "output.snapshot_interval_s=1", "-s", "output.progress_interval_s=0",
                    "--threads", str(args.threads), "-o", folder, "--overwrite"] + extra
            start = time.time()
            r = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, errors="replace",
                               env=study.solver_environment())
            wall = time.time() - start
            status, message = run_outcome(name, folder, r)
            (ke1, ke5, ke_end), reached = kinetic_energy_at(folder, (1.0, 5.0, args.end_s))
            row = {"variant": variant, "dt_ms": dt_ms, "end_s": args.end_s, "status": status, "message": message,
                   "wall_s": "%.1f" % wall, "time_reached_s": "%.4f" % reached, "ke_1s_jpm": "%.3g" % ke1,
                   "ke_5s_jpm": "%.3g" % ke5, "ke_end_jpm": "%.3g" % ke_end}
            study.append_row(args.implicit_csv, IMPLICIT_COLUMNS, row)
            print("stability_map: %s: %s, kinetic energy %s J/m at %g s (%s s)" % (name, status, row["ke_end_jpm"],
                                                                                  args.end_s, row["wall_s"]), flush=True)
    return 0


def implicit_panel(ax, rows):
    """The implicit still tank: step (0: own) against variant, o at rest (kinetic energy at the end within 10 times
    the defaults' at the own step), x stopped or moving."""
    own = [float(r["ke_end_jpm"]) for r in rows if r["variant"] == "defaults" and float(r["dt_ms"]) == 0
           and r["status"] == "healthy"]
    limit = 10 * own[0] if own else float("nan")
    steps = sorted({float(r["dt_ms"]) for r in rows}, key=lambda v: (v == 0, v))
    variants = list(IMPLICIT_VARIANTS)
    for r in rows:
        x = steps.index(float(r["dt_ms"]))
        y = variants.index(r["variant"]) if r["variant"] in variants else len(variants)
        ke = float(r["ke_end_jpm"])
        at_rest = r["status"] == "healthy" and ke <= limit
        ax.scatter(x, y, marker="o" if at_rest else "x", s=80, color="tab:green" if at_rest else "tab:red")
        ax.annotate(("%.1g J/m" % ke) if r["status"] == "healthy" else "stopped %.2f s" % float(r["time_reached_s"]),
                    (x, y), fontsize=7, xytext=(-18, 8), textcoords="offset points")
    ax.set_xticks(range(len(steps)), ["own" if v == 0 else "%g ms" % v for v in steps])
    ax.set_yticks(range(len(variants)), ["images + relaxation" if v == "defaults" else "kernels cut off"
                                          for v in variants])
    ax.set_ylim(-0.6, len(variants) - 0.4)
    ax.set_title("implicit, still tank, %s s at a fixed step" % rows[0]["end_s"], fontsize=10)


def command_chart(args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = study.read_rows("stability_map", args.csv, dict(
        case=str, dp_m=str, end_s=str, shifting=str, status=str, ch=float, cfl=float, c0_factor=float))
    forms = ["none", "velocity", "lind"]
    implicit_rows = study.read_rows("stability_map", args.implicit_csv, dict(
        variant=str, dt_ms=str, end_s=str, status=str, time_reached_s=str, ke_end_jpm=str)) \
        if os.path.isfile(args.implicit_csv) else []
    fig = plt.figure(figsize=(13, 7.5 if implicit_rows else 4))
    grid = fig.add_gridspec(2 if implicit_rows else 1, 3)
    axes = [fig.add_subplot(grid[0, 0])]
    axes += [fig.add_subplot(grid[0, k], sharey=axes[0]) for k in (1, 2)]
    if implicit_rows:
        implicit_panel(fig.add_subplot(grid[1, :]), implicit_rows)
    for ax, form in zip(axes, forms):
        sel = [r for r in rows if r["shifting"] == form]
        c0_factors = sorted({float(r["c0_factor"]) for r in rows})
        for r in sel:
            healthy = r["status"] == "healthy"
            offset = 0.08 * (c0_factors.index(float(r["c0_factor"])) - (len(c0_factors) - 1) / 2)
            x = float(r["ch"]) + offset
            ax.scatter(x, float(r["cfl"]), marker="o" if healthy else "x", s=80,
                       color="tab:green" if healthy else "tab:red")
            ax.annotate("c0x%g" % float(r["c0_factor"]), (x, float(r["cfl"])), fontsize=7, xytext=(-10, 8),
                        textcoords="offset points")
        ax.set_xlim(1.0, 2.1)
        ax.set_title("explicit, shifting = %s" % form)
        ax.set_xlabel("C_h")
    axes[0].set_ylabel("C_CFL")
    failures = sorted({r["status"].replace("failed: ", "") for r in rows if r["status"] != "healthy"})
    fig.suptitle("Stability map (%s, dp = %s m, %s s): o healthy (implicit: at rest), x stopped by the health "
                 "monitor (%s)" %
                 (rows[0]["case"], rows[0]["dp_m"], rows[0]["end_s"], "; ".join(failures) or "none"))
    fig.tight_layout()
    fig.savefig(args.png, dpi=100)
    print("stability_map: wrote %s from %d cells and %d implicit runs" % (args.png, len(rows), len(implicit_rows)))
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("--case", default="id1", choices=["id1", "id2"])
    run.add_argument("--dp", type=cli_checks.positive, default=0.002)
    run.add_argument("--shifting", default="none,velocity,lind", type=cli_checks.names(["none", "velocity", "lind"]))
    run.add_argument("--ch", default="1.3,1.8")
    run.add_argument("--cfl", default="0.2,0.5")
    run.add_argument("--c0-factor", default="10,5")
    run.add_argument("--end-s", type=cli_checks.positive, default=3.0)
    run.add_argument("--threads", type=cli_checks.positive_int, default=2)
    run.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "stability"))
    run.add_argument("--csv", default=os.path.join(ROOT, "studies", "stability", "data", "stability_map.csv"))
    run.add_argument("--frames", type=cli_checks.folder, default=os.path.join(ROOT, "docs", "validation", "stability"))
    run.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    implicit_csv = os.path.join(ROOT, "studies", "stability", "data", "implicit_still_tank.csv")
    implicit = sub.add_parser("implicit-run")
    implicit.add_argument("--steps-ms", default="1,2,3,5,0")
    implicit.add_argument("--end-s", type=cli_checks.positive, default=10.0)
    implicit.add_argument("--threads", type=cli_checks.positive_int, default=1)
    implicit.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "stability"))
    implicit.add_argument("--implicit-csv", default=implicit_csv)
    implicit.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    chart = sub.add_parser("chart")
    chart.add_argument("--implicit-csv", default=implicit_csv)
    chart.add_argument("--csv", default=os.path.join(ROOT, "studies", "stability", "data", "stability_map.csv"))
    chart.add_argument("--png", type=cli_checks.png_file,
                       default=os.path.join(ROOT, "docs", "validation", "stability_map.png"))
    args = parser.parse_args()
    if args.command == "run":
        args.ch = study.positive_numbers("stability_map", args.ch, "ch")
        args.cfl = study.positive_numbers("stability_map", args.cfl, "cfl")
        args.c0_factor = study.positive_numbers("stability_map", args.c0_factor, "c0-factor")
        return command_run(args)
    if args.command == "implicit-run":
        args.steps_ms = non_negative_numbers(args.steps_ms)
        return command_implicit_run(args)
    return command_chart(args)


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
