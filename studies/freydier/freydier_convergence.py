#!/usr/bin/python3
"""Convergence study of the Freydier surges: runs a grid of (case, dp, C_h, shifting) configurations, each in
its own folder, resumable from checkpoints, and appends one row per finished run to a CSV; `chart` plots each
error against wall time (one point per run).

  studies/freydier/freydier_convergence.py run [--cases id1,id2] [--dp 0.001,0.0005] [--ch 1,1.3,1.5,1.8,2.2]
        [--shifting lind] [--shape block] [--continuity renormalised|plain] [--scheme explicit|implicit]
        [--end-s 40] [--threads 2]
        [--budget-s SECONDS]
        [--runs-dir runs/convergence] [--csv studies/freydier/data/freydier_convergence.csv]
  studies/freydier/freydier_convergence.py chart [--csv ...] [--png docs/validation/freydier_accuracy_vs_cost.png]
  studies/freydier/freydier_convergence.py park|unpark [--runs-dir runs/convergence]
        [--parked-dir studies/freydier/parked]

A run interrupted (Ctrl-C, --budget-s, the machine taken back) keeps its checkpoint; the next `run` continues it, and
its wall time adds up across the pieces (progress.json in its folder). runs/ is not committed, so a run that must
outlive the checkout is parked: `park` copies each interrupted run's checkpoint, small files and initial snapshot
(compressed) into studies/freydier/parked/, which is committed; `unpark` in a fresh checkout puts them back, and
`run` with the same options continues. A finished run's parked copy is deleted by `run`.

The `corner` column names the solver's belt-upstream-wall corner (docs/method.md): rows written before it existed
ran with the bed under the wall moving with the belt (`belt`); this tool runs the current code (`split`: moving
with the belt in continuity, fixed for no-slip), in folders named with that suffix, and a grid point counts as
done only when it has a row for the current corner.
"""
import argparse
import os
import shutil
import subprocess
import sys
import time

from surgepy import cli_checks, study

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

COLUMNS = ["case", "dp_m", "ch", "shifting", "shape", "threads", "wall_s", "particle_steps", "sim_time_s",
           "zeta_f", "zeta_h", "zeta_fs", "zeta_u_076", "zeta_u_150", "zeta_u_970", "status", "continuity", "corner",
           "scheme"]
METRICS = ["zeta_f", "zeta_h", "zeta_fs", "zeta_u_076", "zeta_u_150", "zeta_u_970"]


def fail(message):
    study.fail("freydier_convergence", message)


PARKED_DIR = os.path.join(ROOT, "studies", "freydier", "parked")
CORNER = "split"  # the belt-upstream-wall corner of the current solver (sim/src/scene/scene.c)


def run_name(case, dp, ch, shifting, shape, continuity, scheme):
    """Runs with the plain continuity equation, or the explicit scheme, keep the names they had before the choice
    existed."""
    return "%s_dp%g_ch%g_%s_%s%s_corner-%s%s" % (case, dp, ch, shifting, shape,
                                                "" if continuity == "plain" else "_" + continuity, CORNER,
                                                "" if scheme == "explicit" else "_" + scheme)


def scheme_of(row):
    """Rows written before the scheme column existed ran the explicit scheme."""
    return row.get("scheme") or "explicit"


def continuity_of(row):
    """Rows written before the continuity column existed used the plain form."""
    return row.get("continuity") or "plain"


def corner_of(row):
    """Rows written before the corner column existed ran with the bed under the upstream wall moving with the belt."""
    return row.get("corner") or "belt"


def finished(rows):
    """Grid points with a successful run; a failed one stays in the CSV as a record and is run again (fresh)."""
    return {(r["case"], float(r["dp_m"]), float(r["ch"]), r["shifting"], r.get("shape", "block"),
             continuity_of(r), scheme_of(r)) for r in rows if r["status"] == "ok" and corner_of(r) == CORNER}


def run_one(args, case, dp, ch, deadline):
    name = run_name(case, dp, ch, args.shifting, args.shape, args.continuity, args.scheme)
    folder = os.path.join(args.runs_dir, name)
    common = ["-s", "time.end_s=%g" % args.end_s, "-s", "output.progress_interval_s=60", "--threads",
              str(args.threads)]
    fresh = [args.surge, "run", os.path.join(ROOT, "cases", "freydier_%s.ini" % case),
             "-s", "numerics.dp_m=%g" % dp, "-s", "numerics.ch=%g" % ch, "-s", "walls.layers=0",
             "-s", "shifting.form=%s" % args.shifting, "-s", "fluid.shape=%s" % args.shape,
             "-s", "numerics.continuity_correction=%s" % ("true" if args.continuity == "renormalised" else "false"),
             "-s", "numerics.scheme=%s" % args.scheme, "-o", folder, "--overwrite"]  # the study owns its folders: a fresh start replaces a failed piece
    rc, progress = study.run_resumable("freydier_convergence: " + name, folder, fresh, args.surge, common, deadline)
    if rc == 4:
        return False
    steps, sim_time = study.particle_steps("freydier_convergence", folder)
    row = {"case": case, "dp_m": dp, "ch": ch, "shifting": args.shifting, "shape": args.shape,
           "continuity": args.continuity, "corner": CORNER, "scheme": args.scheme,
           "threads": args.threads, "wall_s": "%.1f" % progress["wall_s"], "particle_steps": steps,
           "sim_time_s": "%.3f" % sim_time}
    if rc == 0:
        metrics = subprocess.run([sys.executable, os.path.join(ROOT, "tools", "freydier_metrics.py"), folder,
                                  "--csv-row", "--png", os.path.join(folder, "metrics.png")],
                                 capture_output=True, text=True)
        if metrics.returncode != 0:
            row.update({m: "nan" for m in METRICS})
            row["status"] = "metrics failed: " + metrics.stderr.strip().splitlines()[-1]
        else:
            values = metrics.stdout.strip().splitlines()[-1].split(",")
            row.update(dict(zip(METRICS, values)))
            row["status"] = "ok"
    else:
        row.update({m: "nan" for m in METRICS})
        row["status"] = "exit %d (health monitor)" % rc if rc == 1 else "exit %d" % rc
    progress["status"] = row["status"]
    study.write_progress(folder, progress)
    study.append_row(args.csv, COLUMNS, row)
    shutil.rmtree(os.path.join(args.parked_dir, name), ignore_errors=True)
    print("freydier_convergence: %s: %s" % (name, row), flush=True)
    return True


def command_run(args):
    done = finished(study.existing_rows("freydier_convergence", args.csv, COLUMNS, dict(
        case=str, dp_m=float, ch=float, shifting=str, status=str)))
    deadline = time.time() + args.budget_s if args.budget_s else None
    for case in args.cases:
        for dp in args.dp:
            for ch in args.ch:
                if (case, dp, ch, args.shifting, args.shape, args.continuity, args.scheme) in done:
                    continue
                if deadline and time.time() > deadline:
                    print("freydier_convergence: budget spent; run again to continue", flush=True)
                    return 0
                if not run_one(args, case, dp, ch, deadline):
                    print("freydier_convergence: interrupted; run again to continue", flush=True)
                    return 0
    return 0


def command_chart(args):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter
    rows = [r for r in study.read_rows("freydier_convergence", args.csv, dict(
        case=str, ch=str, threads=str, status=str, dp_m=float, wall_s=float, **dict.fromkeys(METRICS, float)))
        if r["status"] == "ok"]
    if not rows:
        fail("%s: no finished runs to chart" % args.csv)
    targets = {"zeta_f": 0.01, "zeta_h": 0.05, "zeta_fs": 0.10, "zeta_u_076": 0.05, "zeta_u_150": 0.05,
               "zeta_u_970": 0.05}
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5), sharex=True)
    colour_of = {dp: "C%d" % k for k, dp in enumerate(sorted({float(r["dp_m"]) for r in rows}))}
    for ax, metric in zip(axes.flat, METRICS):
        earlier = [r for r in rows if corner_of(r) != CORNER]
        if earlier:
            ax.scatter([float(r["wall_s"]) for r in earlier], [float(r[metric]) for r in earlier], marker="x",
                       color="0.7", label="earlier corner (belt or gate; see the corner column)")
        for case, marker in (("id1", "o"), ("id2", "s")):
            for continuity in ("plain", "renormalised"):
                for dp in sorted({float(r["dp_m"]) for r in rows if r["case"] == case}):
                    sel = [r for r in rows if r["case"] == case and float(r["dp_m"]) == dp
                           and continuity_of(r) == continuity and corner_of(r) == CORNER
                           and scheme_of(r) == "explicit"]
                    if not sel:
                        continue
                    xs = [float(r["wall_s"]) for r in sel]
                    ys = [float(r[metric]) for r in sel]
                    ax.scatter(xs, ys, marker=marker, facecolors="none" if continuity == "plain" else None,
                               edgecolors=colour_of[dp], color=None if continuity == "plain" else colour_of[dp],
                               label="%s dp=%g mm, %s continuity" % (case.upper(), dp * 1e3, continuity))
                    for r, x, y in zip(sel, xs, ys):
                        ax.annotate("C_h %s, %s thr" % (r["ch"], r["threads"]), (x, y), fontsize=6, xytext=(3, 3),
                                    textcoords="offset points")
        for case in ("id1", "id2"):
            for dp in sorted({float(r["dp_m"]) for r in rows if r["case"] == case}):
                sel = [r for r in rows if r["case"] == case and float(r["dp_m"]) == dp and scheme_of(r) == "implicit"
                       and corner_of(r) == CORNER]
                if not sel:
                    continue
                xs, ys = [float(r["wall_s"]) for r in sel], [float(r[metric]) for r in sel]
                ax.scatter(xs, ys, marker="*", s=90, color=colour_of[dp],
                           label="%s dp=%g mm, implicit scheme" % (case.upper(), dp * 1e3))
                for r, x, y in zip(sel, xs, ys):
                    ax.annotate("C_h %s, %s thr" % (r["ch"], r["threads"]), (x, y), fontsize=6, xytext=(3, 3),
                                textcoords="offset points")
        ax.axhline(targets[metric], color="grey", ls="--", lw=1)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_title("%s (target %g, dashed)" % (metric, targets[metric]))
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("error (fraction)")
    axes.flat[0].legend(fontsize=8)
    fig.suptitle("Freydier surges: accuracy against cost, one point per run (hollow: plain continuity; "
                 "grey x: runs with an earlier belt-wall corner)")
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print("freydier_convergence: wrote %s from %d runs" % (args.png, len(rows)))
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("--cases", default="id1,id2", type=cli_checks.names(["id1", "id2"]))
    run.add_argument("--dp", default="0.001,0.0005")
    run.add_argument("--ch", default="1,1.3,1.5,1.8,2.2")
    run.add_argument("--shifting", default="lind", choices=["none", "velocity", "lind"])
    run.add_argument("--shape", default="block", choices=["block", "lubrication"])
    run.add_argument("--continuity", default="renormalised", choices=["renormalised", "plain"],
                     help="numerics.continuity_correction true (renormalised, the default) or false (plain)")
    run.add_argument("--scheme", default="explicit", choices=["explicit", "implicit"],
                     help="numerics.scheme (docs/method.md); implicit runs are drawn as stars")
    run.add_argument("--end-s", type=cli_checks.positive, default=40.0)
    run.add_argument("--threads", type=cli_checks.positive_int, default=2)
    run.add_argument("--budget-s", type=cli_checks.non_negative, default=0.0)
    run.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "convergence"))
    run.add_argument("--csv", default=os.path.join(ROOT, "studies", "freydier", "data", "freydier_convergence.csv"))
    run.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    run.add_argument("--parked-dir", type=cli_checks.folder, default=PARKED_DIR)
    for command in ("park", "unpark"):
        parking = sub.add_parser(command)
        parking.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "convergence"))
        parking.add_argument("--parked-dir", type=cli_checks.folder, default=PARKED_DIR)
    chart = sub.add_parser("chart")
    chart.add_argument("--csv", default=os.path.join(ROOT, "studies", "freydier", "data", "freydier_convergence.csv"))
    chart.add_argument("--png", type=cli_checks.png_file,
                       default=os.path.join(ROOT, "docs", "validation", "freydier_accuracy_vs_cost.png"))
    args = parser.parse_args()
    if args.command == "run":
        args.dp = study.positive_numbers("freydier_convergence", args.dp, "dp")
        args.ch = study.positive_numbers("freydier_convergence", args.ch, "ch")
        return command_run(args)
    if args.command == "park":
        return study.park_command("freydier_convergence", args.runs_dir, args.parked_dir)
    if args.command == "unpark":
        return study.unpark_command("freydier_convergence", args.parked_dir, args.runs_dir)
    return command_chart(args)


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
