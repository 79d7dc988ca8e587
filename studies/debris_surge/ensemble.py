#!/usr/bin/python3
"""The boulder-laden debris surge (GMD 2025 Sect. 3.3, Table 3, Fig. 7) as an ensemble: N seeds per boulder count
or solid fraction, each a run of cases/debris_surge.ini with graded boulders (docs/boulders.md), and the statistics
of their Froude number and equivalent viscosity (eq. 21, from each run's flow.csv). docs/validation/debris_surge.md
says more.

  studies/debris_surge/ensemble.py run [--counts 0,50,100,154] [--phis F,...] [--seeds 5] [--dp 0.05] [--end-s 75]
        [--threads 1] [--jobs 1] [--member K] [--budget-s S] [--runs-dir runs/debris_surge] [--set NAME=VALUE ...]
        [--continue-stopped] [--parked-dir studies/debris_surge/parked]
  studies/debris_surge/ensemble.py park|unpark [--runs-dir runs/debris_surge]
        [--parked-dir studies/debris_surge/parked]
  studies/debris_surge/ensemble.py collect [--runs-dir runs/debris_surge] [--window 20 75] [--csv FILE]
        [--png FILE]
  studies/debris_surge/ensemble.py plot --csv FILE [--csv FILE ...] --png FILE
  studies/debris_surge/ensemble.py compare --csv A --csv B [--window-tolerance-s 0.5]
  studies/debris_surge/ensemble.py lift RUN_DIR [RUN_DIR ...] [--window 6 20]
  studies/debris_surge/ensemble.py shape RUN_DIR [RUN_DIR ...] [--window 6 20] [--body START_M END_M] [--csv FILE]
  studies/debris_surge/ensemble.py history RUN_DIR [RUN_DIR ...] [--window 0 75] [--block-s 2] [--csv FILE]
        [--png FILE]
  studies/debris_surge/ensemble.py list [--counts ...] [--phis ...] [--seeds ...] [--dp ...]

run: the members are (count, seed) pairs, count 0 once (the fluid alone has no randomness), the others with seeds
1..N, then (solid fraction, seed) pairs, seeds 1..N: graded discs drawn until they cover that fraction of the fluid
block (the paper's phi = 0.53, say; --counts defaults to none when --phis is given); each runs in its own folder
runs-dir/n<count>_s<seed>_dp<dp> or runs-dir/phi<fraction>_s<seed>_dp<dp>, resumable (an interrupted member continues
from its checkpoint, a finished one is skipped (or, when --end-s asks for more flow than its checkpoint holds,
continued from there to the new end, recorded in progress.json as extended_from_s), and so is one the health
monitor stopped, whose folder keeps its
last good state (last_good.vtp, last_good.bin); --continue-stopped continues such members from that state, passing the --set parameters, which
must then be live ones such as health.max_density_deviation, and records them in progress.json). --member K runs
only the K-th member of `list` (0-based), for a
job-array scheduler; --jobs J runs J members at a time (with --threads each). The boulders have the paper's
density ratio 0.9. --set NAME=VALUE (repeatable) passes a parameter to every member's first run; `surge check`
vets them before any member starts, and each member's params.ini records them. The case's automatic c0 carries
discs (112 m/s; docs/method.md, "c0"); the ensembles at dp = 0.04 m in docs/validation/debris_surge.md ran with
--set numerics.c0_mps=110 and keep it for their remaining members.
park / unpark: a member longer than one sitting is carried in the committed tree, since nothing else survives from
one checkout to the next: `park` copies each interrupted (or still running) member's last checkpoint, flow.csv,
boulders.csv and small files (the checkpoint gzip-compressed; no snapshot, which collect does not read: 0.57 MB
for 60 discs at dp = 0.04 m, measured 2026-11-28) into studies/debris_surge/parked/; `unpark` in a fresh
checkout puts them back, and the same `run` continues each from its checkpoint, bit for bit. A member that finishes
deletes its parked copy. Resume with the surge that started the member: its progress.json lists the programs that
ran it (`surge version`: commit, compiler, vector extensions), and a member continued under another says so.
collect: per member (its folder's n<count> or phi<fraction> in the table's asked column, the discs it placed in
count), the means of Fr and mu_eq/mu0 over the window (the paper's 20-75 s; a run that ends before
25 s is averaged over its second half, and the window used is written) with their standard errors (froude_se,
mu_eq_over_mu0_se: one member's window mean, its rows' autocorrelation counted; not the spread over seeds), how
many discs rest on the belt (boulders_on_belt: at the contact margin from the belt's face, within 0.05 dp; the
mean over the window's disc snapshots, with its standard error; nan without them) and the forces normal to the belt
(away from it) on the discs resting on it, summed over them and averaged over the same snapshots (on_belt_weight_npm:
their weight, m g cos(slope); on_belt_fluid_npm, on_belt_film_npm, on_belt_disc_contact_npm and
on_belt_bed_contact_npm, from the snapshots' forces: the fluid's, the films', the other discs' and the belt's;
over the snapshots that carry them, nan where none does; at rest the last four balance the first), the mean contact forces on the
discs over the window (bed_, wall_ and disc_normal_force_npm, and the same _friction_force_npm: N per metre of width,
of the belt, of the other walls and between discs; nan in a flow.csv without them) and the most discs that were ever ahead of
the front (discs that left the surge, which may then roll round the period); a table (--csv) and box plots of Fr and
mu_eq/mu0 against the realised solid fraction phi (disc area over the initial fluid block's; boxes the quartiles,
whiskers the extremes, the mean marked), with the uniform-flow values for phi = 0 (--png); the table's
max_density_deviation is the largest |rho/rho0 - 1| of the fluid over the run, as diagnostics.csv sampled it.
plot: the same box plots from one or more tables that collect wrote (--csv), or that were written by hand with its
columns asked, seed, dp_m, phi, window_start_s, window_end_s, froude, mu_eq_over_mu0 and uniform_froude (members
whose folders are gone; other columns may be empty), one box per dp and asked; a member given twice, a value out of
range, or rows averaged over windows further apart than --window-tolerance-s (default 0.5 s) are refused.
compare: two tables that collect wrote (two schemes, two resolutions, two builds), member by member: the members
that asked for the same discs (asked) with the same seed, whatever their dp; per member each table's Fr and
mu_eq/mu0 with their standard errors and B against A (relative difference, and in units of the two errors combined),
then the same for the means over the members in both, the errors of the means from the seeds' spread (nan for one
member), and the members only one table has. A member twice in one table, an asked that is neither n<count> nor
phi<fraction>, a value that is not finite or not positive, or windows further apart than --window-tolerance-s are
refused, naming the file and the line.
lift: how much of their buoyancy the fluid gives the discs, per run folder with particle snapshots (run.pvd) and disc
snapshots at the same times, averaged over the window's snapshots: the fluid's force on all discs normal to the belt
(fluid_lift_npm, the snapshots' fluid_force_npm), the hydrostatic buoyancy of their submerged parts (rho g cos(slope)
times each disc's area below the local surface, the highest fluid particle within its radius + 2 dp along the belt,
plus half a spacing), their ratio (lift_share: 1 where the fluid round every disc is hydrostatic and at rest), and the
fluid's pressure over the hydrostatic pressure under the local surface (the highest fluid particle in columns
0.1 m wide), summed over the fluid more than 4 dp deep: touching the discs (within 1 dp of a disc's face), the next
row (1-2 dp), and farther than 8 dp from every disc; and the share of the fluid particles below 0 Pa (in tension) with
the lowest pressure, over all the snapshots' fluid. Disc snapshots without the forces (a run's first) are skipped. A
folder without both snapshot series, without discs, with a value that is not a number, or with no snapshot pair in the
window that carries the forces is refused, named.
shape: the surge's mean shape over the window, per run folder with particle snapshots (run.pvd): the height of the
fluid's surface above the belt's face (the highest fluid particle plus half a spacing, 0 where a column is dry) in
columns output.flow_column_m wide along the belt, by distance downstream of the upstream wall's face, averaged over
the window's snapshots; the mean of that profile over the body (--body, m from the wall's face; default the 5 m
after flow.csv's ignored zone, output.flow_ignore_m); the mean front (flow.csv's front_from_wall_m over the same
window); and, from the disc snapshots at the same times where they exist, the mean distance of the disc centres from
the wall's face and their mean height above the belt's face. --csv writes the profiles, one column per folder. A
folder without particle snapshots in the window, or with a value that is not a number, is refused, named.
history: how Fr and mu_eq/mu0 move over a run, per run folder: their means over consecutive blocks of --block-s
(default 2 s) from the window's start, each block the flow.csv rows at start <= t < end (the first row, before the
flow moves, has mu_eq/mu0 infinite and is left out, as is any row that is not finite), a block only where the run
reached its end; printed, written one row per block with two columns per folder (--csv; empty where a run did not
reach the block) and drawn against time (--png): two runs that part over one window may run in step over the next,
or their pulses against each other. A folder without flow.csv, or a window no block of any run fits, is refused.
"""
import argparse
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import threading
import time

import numpy as np

from surgepy import cli_checks, study, vtp
from surgepy.run_params import ParamsError, RunParams

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

TOOL = "ensemble"
CASE = os.path.join(ROOT, "cases", "debris_surge.ini")
PARKED_DIR = os.path.join(ROOT, "studies", "debris_surge", "parked")
PARKED_EXTRA = ("flow.csv", "boulders.csv")  # eq. 21's rows from the start, and the disc list (phi)
COLUMNS = ["asked", "count", "seed", "dp_m", "phi", "window_start_s", "window_end_s", "rows", "froude",
           "froude_se", "mu_eq_over_mu0", "mu_eq_over_mu0_se", "h_max_m", "u_bar_mps", "boulders_behind_front_m",
           "boulders_on_belt", "boulders_on_belt_se", "on_belt_weight_npm", "on_belt_fluid_npm", "on_belt_film_npm",
           "on_belt_disc_contact_npm", "on_belt_bed_contact_npm", "bed_normal_force_npm", "bed_friction_force_npm",
           "wall_normal_force_npm", "wall_friction_force_npm", "disc_normal_force_npm", "disc_friction_force_npm",
           "most_boulders_ahead", "end_s", "wall_s", "status", "uniform_froude", "max_density_deviation"]
PLOTTED = {"asked": str, "seed": int, "dp_m": float, "phi": float, "window_start_s": float, "window_end_s": float,
           "froude": float, "mu_eq_over_mu0": float, "uniform_froude": float}  # the columns `plot` reads from a table
PLOTTED_RANGES = {"dp_m": (0.0, 1.0), "phi": (0.0, 1.0), "froude": (0.0, 100.0), "mu_eq_over_mu0": (0.0, 1e4),
                  "uniform_froude": (0.0, 100.0), "window_start_s": (0.0, 1e6), "window_end_s": (0.0, 1e6)}
COMPARED = {"asked": str, "seed": int, "dp_m": float, "window_start_s": float, "window_end_s": float,
            "froude": float, "froude_se": float, "mu_eq_over_mu0": float, "mu_eq_over_mu0_se": float}
ZERO_ALLOWED = ("phi", "window_start_s")  # the fluid alone, a window from the start; every other bound is open
SNAPSHOT_FORCES = {"on_belt_fluid_npm": "fluid_force_npm", "on_belt_film_npm": "film_force_npm",
                   "on_belt_disc_contact_npm": "disc_contact_force_npm",
                   "on_belt_bed_contact_npm": "wall_contact_force_npm"}  # collect's columns: a snapshot array's y
ON_BELT_FORCES = ("on_belt_weight_npm",) + tuple(SNAPSHOT_FORCES)
ON_BELT_DP = 0.05  # a disc rests on the belt when its gap to the belt's face is the contact margin to within this
LIFT_COLUMN_M = 0.1  # lift: the local surface is the highest fluid particle in columns this wide along the belt
LIFT_DEEP_DP = 4.0  # lift: the pressure is read where the fluid lies deeper than this below the local surface
LIFT_BANDS_DP = (("touching", 0.0, 1.0), ("next_row", 1.0, 2.0), ("far", 8.0, math.inf))  # from the nearest disc face
WINDOW_TOLERANCE_S = 0.5  # one flow.csv row: the windows of members that ran as long agree to this (plot's default)


def fail(message):
    study.fail(TOOL, message)


def write_csv(path, rows, lineterminator="\r\n"):
    """Writes rows, the header first, to the CSV file path (--csv); a write the system refuses ends the tool, named."""
    try:
        with open(path, "w", newline="") as f:
            csv.writer(f, lineterminator=lineterminator).writerows(rows)
    except OSError as e:
        fail("--csv %s: cannot write it (%s)" % (path, e.strerror or e))


def counts_list(text):
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("expected comma-separated whole numbers, got '%s'" % text)
    if not values or any(v < 0 or v > 20000 for v in values) or len(set(values)) != len(values):
        raise argparse.ArgumentTypeError("expected distinct disc counts in [0, 20000], got '%s'" % text)
    return values


def setting_arg(text):
    """NAME=VALUE with NAME a section.key of the parameter registry (surge check vets the rest)."""
    name, equals, value = text.partition("=")
    if not equals or not value or name.count(".") != 1 or not all(name.split(".")):
        raise argparse.ArgumentTypeError("expected section.key=value, got '%s'" % text)
    return text


def phis_list(text):
    """Solid fractions in [0.001, 0.8], distinct as written in folder names and settings (%g)"""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError("expected comma-separated solid fractions, got '%s'" % text)
    if not values or any(not 0.001 <= v <= 0.8 for v in values) or len(set("%g" % v for v in values)) != len(values):
        raise argparse.ArgumentTypeError("expected solid fractions in [0.001, 0.8], distinct to 6 digits, got '%s'"
                                         % text)
    return values


def members(args):
    """[(asked, seed)] in a fixed order: the disc counts (count 0 once, every other count with seeds 1..N), then the
    solid fractions, each with seeds 1..N. asked is ("n", count) or ("phi", solid fraction)."""
    by_count = [(("n", c), s) for c in args.counts for s in ([1] if c == 0 else range(1, args.seeds + 1))]
    return by_count + [(("phi", f), s) for f in args.phis for s in range(1, args.seeds + 1)]


def asked_name(asked):
    """n<count> or phi<solid fraction>: the start of a member's folder name"""
    return "n%d" % asked[1] if asked[0] == "n" else "phi%g" % asked[1]


def folder_of(args, asked, seed):
    return os.path.join(args.runs_dir, "%s_s%d_dp%g" % (asked_name(asked), seed, args.dp))


def scene_settings(args, asked, seed):
    """The -s options of a member's scene: dp, its graded discs (by count, or drawn until they cover the solid
    fraction of the fluid block; boulder_scene.c) and the --set parameters"""
    settings = ["numerics.dp_m=%g" % args.dp]
    if asked != ("n", 0):
        settings += ["boulders.placement=graded", "boulders.seed=%d" % seed, "boulders.density_ratio=0.9"]
        settings += (["boulders.count=%d" % asked[1]] if asked[0] == "n" else
                     ["boulders.count=0", "boulders.solid_fraction=%g" % asked[1]])
    return [item for setting in settings + args.set for item in ("-s", setting)]


def run_member(args, asked, seed, deadline):
    folder = folder_of(args, asked, seed)
    try:
        progress = study.read_progress(folder) if os.path.isdir(folder) else {"status": "new"}
    except ValueError as e:
        fail(str(e))
    if progress["status"] == "done":
        checkpoint = os.path.join(folder, "checkpoint.bin")
        try:
            reached_s = study.checkpoint_time(checkpoint)[1] if os.path.isfile(checkpoint) else None
        except ValueError as e:
            fail(str(e))
        if reached_s is None or reached_s >= args.end_s - 1e-6:
            print("%s: %s: done already" % (TOOL, folder), flush=True)
            return
        progress["status"] = "interrupted"  # a longer --end-s continues a finished member from its last checkpoint
        progress["extended_from_s"] = progress.get("extended_from_s", []) + [round(reached_s, 6)]
        study.write_progress(folder, progress)
    continued, checkpoint_name = [], "checkpoint.bin"
    if progress["status"] == "unhealthy":  # the same run would stop again; its last_good.vtp and .bin stay
        if not args.continue_stopped:
            print("%s: %s: stopped by the health monitor earlier (see its last_good.vtp); remove the folder to run it "
                  "again, or continue it from its last good state with --continue-stopped and a --set that lets it "
                  "through" % (TOOL, folder), flush=True)
            return
        checkpoint_name = "last_good.bin"
        if not os.path.isfile(os.path.join(folder, checkpoint_name)):
            fail("%s: stopped by the health monitor, but its last_good.bin (the last good state) is missing" % folder)
        continued = [item for setting in args.set for item in ("-s", setting)]
        progress["status"] = "interrupted"  # run_resumable continues an interrupted member from its checkpoint
        progress["continued_with"] = progress.get("continued_with", []) + [args.set]
        study.write_progress(folder, progress)
    fresh = [args.surge, "run", CASE, "-o", folder, "--overwrite"] + scene_settings(args, asked, seed)
    common = ["-s", "time.end_s=%g" % args.end_s, "-s", "output.checkpoint_interval_s=5",
              "-s", "output.progress_interval_s=60", "--threads", str(args.threads)]
    rc, progress = study.run_resumable(TOOL, folder, fresh, args.surge, common + continued, deadline, checkpoint_name)
    if rc != 4:
        progress["status"] = "done" if rc == 0 else "unhealthy"
        study.write_progress(folder, progress)
    if rc == 0:
        shutil.rmtree(os.path.join(args.parked_dir, os.path.basename(folder)), ignore_errors=True)


def live_parameters(surge):
    """The section.key names that `surge params` marks live (those a restart may change)."""
    listing = subprocess.run([surge, "params"], capture_output=True, text=True)
    if listing.returncode != 0:
        fail("%s params failed: %s" % (surge, listing.stderr.strip()[-500:]))
    live, section = set(), None
    for line in listing.stdout.splitlines():
        heading = re.match(r"## \[(\w+)\]", line)
        if heading:
            section = heading.group(1)
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if section and len(cells) >= 6 and cells[0].startswith("`") and cells[5] == "yes":
            live.add("%s.%s" % (section, cells[0].strip("`")))
    return live


def command_run(args):
    chosen = members(args)
    if args.member is not None:
        if not 0 <= args.member < len(chosen):
            fail("--member %d: the ensemble has members 0..%d (see the list command)" % (args.member, len(chosen) - 1))
        chosen = [chosen[args.member]]
    if args.set:
        vet = [args.surge, "check", CASE, "-s", "numerics.dp_m=%g" % args.dp]
        for setting in args.set:
            vet += ["-s", setting]
        checked = subprocess.run(vet, capture_output=True, text=True)
        if checked.returncode != 0:
            fail("--set: %s" % (checked.stderr.strip().splitlines() or ["surge check failed"])[-1])
    for asked, seed in chosen:  # a new member's discs must fit (placement), before any member runs for hours
        if asked != ("n", 0) and not os.path.isdir(folder_of(args, asked, seed)):
            checked = subprocess.run([args.surge, "check", CASE] + scene_settings(args, asked, seed),
                                     capture_output=True, text=True)
            if checked.returncode != 0:
                fail("member %s: %s" % (os.path.basename(folder_of(args, asked, seed)),
                                        (checked.stderr.strip().splitlines() or ["surge check failed"])[-1]))
    if args.continue_stopped:
        fixed = sorted(set(setting.split("=", 1)[0] for setting in args.set) - live_parameters(args.surge))
        if fixed:
            fail("--continue-stopped: %s cannot change when a run continues from its checkpoint (only live "
                 "parameters can; see surge params)" % ", ".join(fixed))
    deadline = time.time() + args.budget_s if args.budget_s > 0 else None
    os.makedirs(args.runs_dir, exist_ok=True)
    queue, lock = list(chosen), threading.Lock()

    def worker():
        while True:
            with lock:
                if not queue:
                    return
                asked, seed = queue.pop(0)
            if deadline and time.time() > deadline:
                return
            run_member(args, asked, seed, deadline)

    workers = [threading.Thread(target=worker) for _ in range(min(args.jobs, len(chosen)))]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    return 0


def window_means(flow_csv, window):
    """Means over the window of flow.csv's rows; (start, end, rows, {column: mean}, end of the run, {column: standard
    error of the mean} for Fr and mu_eq/mu0, the rows' autocorrelation counted: study.mean_with_error). A run that
    ends before window start + 5 s is averaged over its second half."""
    columns = ("time_s", "froude", "mu_eq_over_mu0", "h_max_m", "u_bar_mps", "boulders_behind_front_m")
    rows = [{k: float(r[k]) for k in columns}
            for r in study.read_rows(TOOL, flow_csv, {k: float for k in columns})]
    end = rows[-1]["time_s"]
    start, stop = (window[0], min(window[1], end)) if end >= window[0] + 5 else (0.5 * end, end)
    chosen = [r for r in rows if start <= r["time_s"] <= stop + 1e-9]
    if not chosen:
        fail("%s: no rows between %g and %g s" % (flow_csv, start, stop))
    means = {k: sum(r[k] for r in chosen) / len(chosen)
             for k in ("froude", "mu_eq_over_mu0", "h_max_m", "u_bar_mps", "boulders_behind_front_m")}
    errors = {k: study.mean_with_error([r[k] for r in chosen])[1] for k in ("froude", "mu_eq_over_mu0")}
    return start, stop, len(chosen), means, end, errors


CONTACT_FORCES = ("bed_normal_force_npm", "bed_friction_force_npm", "wall_normal_force_npm", "wall_friction_force_npm",
                  "disc_normal_force_npm", "disc_friction_force_npm")


def contact_forces(flow_csv, start, stop):
    """{column: mean over the window} of flow.csv's contact forces on the discs (N/m; each row is the mean since the
    row before, so the rows after the window's start are averaged); nan for a flow.csv written before those columns."""
    with open(flow_csv, newline="") as f:
        columns = csv.DictReader(f).fieldnames or []
    if not all(k in columns for k in CONTACT_FORCES):
        return {k: math.nan for k in CONTACT_FORCES}
    rows = [r for r in study.read_rows(TOOL, flow_csv, dict({k: float for k in CONTACT_FORCES}, time_s=float))
            if start < float(r["time_s"]) <= stop + 1e-9]
    return {k: sum(float(r[k]) for r in rows) / len(rows) if rows else math.nan for k in CONTACT_FORCES}


def most_boulders_ahead(flow_csv):
    """The most discs ever downstream of the front over the run (flow.csv's boulders_ahead_of_front: discs that
    left the surge); nan for a flow.csv written before that column existed."""
    with open(flow_csv, newline="") as f:
        columns = csv.DictReader(f).fieldnames or []
    if "boulders_ahead_of_front" not in columns:
        return float("nan")
    return max(int(r["boulders_ahead_of_front"])
               for r in study.read_rows(TOOL, flow_csv, {"boulders_ahead_of_front": int}))


def boulders_on_belt(folder, start, stop):
    """(mean, standard error, forces) over the window's disc snapshots (boulders.pvd) of how many discs rest on the
    belt: a disc whose gap to the belt's face (y = 0, walls.bottom) is the contact margin (contacts.margin_dp), where
    the contact solver holds it, to within ON_BELT_DP; (nan, nan) without disc snapshots in the window. forces: the
    ON_BELT_FORCES, the mean over those of the snapshots that carry the forces (not those written before they did,
    nor a run's first) of the sums over the discs resting in each; nan where none does."""
    pvd = os.path.join(folder, "boulders.pvd")
    forces = {k: [] for k in ON_BELT_FORCES}
    if not os.path.isfile(pvd):
        return math.nan, math.nan, {k: math.nan for k in ON_BELT_FORCES}
    try:
        p = RunParams(folder)
        reach_m = (p.real("contacts", "margin_dp") + ON_BELT_DP) * p.positive("numerics", "dp_m")
        disc_density = p.positive("fluid", "density_kgpm3") * p.positive("boulders", "density_ratio")
        g_normal = p.positive("body", "gravity_mps2") * math.cos(math.radians(p.real("body", "slope_deg")))
        counts = []
        for time_s, name in vtp.read_pvd(pvd):
            if start <= time_s <= stop + 1e-9:
                discs = vtp.read_vtp(os.path.join(folder, name), required=("radius_m",), finite=True)
                resting = discs["points"][:, 1] - discs["radius_m"] <= reach_m
                counts.append(int(resting.sum()))
                if all(a in discs and np.all(np.isfinite(discs[a])) for a in SNAPSHOT_FORCES.values()):
                    forces["on_belt_weight_npm"].append(
                        float((math.pi * discs["radius_m"][resting] ** 2).sum() * disc_density * g_normal))
                    for column, array in SNAPSHOT_FORCES.items():
                        forces[column].append(float(discs[array][resting, 1].sum()))
    except (ParamsError, vtp.VtpError) as e:
        fail(str(e))
    mean, error, _ = study.mean_with_error(counts)
    return mean, error, {k: sum(v) / len(v) if v else math.nan for k, v in forces.items()}


def submerged_area(radius, surface_above_bottom):
    """Area of a disc of this radius below a line this high above its lowest point (0 below it, the whole disc above)."""
    offset = np.clip(surface_above_bottom, 0.0, 2.0 * radius) - radius  # the line's height above the centre
    return radius ** 2 * np.arccos(-offset / radius) + offset * np.sqrt(radius ** 2 - offset ** 2)


def lift(folder, start, stop):
    """(snapshot pairs, discs, fluid_lift_npm, buoyancy_npm, {band: pressure ratio}) over the window: see `lift` in the
    module's text."""
    try:
        p = RunParams(folder)
        rho, dp = p.positive("fluid", "density_kgpm3"), p.positive("numerics", "dp_m")
        g_normal = p.positive("body", "gravity_mps2") * math.cos(math.radians(p.real("body", "slope_deg")))
        series = []
        for name in ("run.pvd", "boulders.pvd"):
            path = os.path.join(folder, name)
            if not os.path.isfile(path):
                fail("%s: no %s (lift reads the particle and the disc snapshots)" % (folder, name))
            series.append({t: f for t, f in vtp.read_pvd(path) if start <= t <= stop + 1e-9})
        times = sorted(set(series[0]) & set(series[1]))
        if not times:
            fail("%s: no particle and disc snapshots at the same time within %g-%g s" % (folder, start, stop))
        lifts, buoyancies, sums = [], [], {band: [0.0, 0.0] for band, _, _ in LIFT_BANDS_DP}
        in_tension, particles_read, lowest_pa = 0, 0, math.inf
        for t in times:
            discs = vtp.read_vtp(os.path.join(folder, series[1][t]), required=("radius_m", "fluid_force_npm"))
            if not np.all(np.isfinite(discs["fluid_force_npm"])):
                continue  # a run's first disc snapshot, written before any force acted
            particles = vtp.read_vtp(os.path.join(folder, series[0][t]), required=("kind", "pressure_pa"),
                                     finite=True)
            radius, centre = discs["radius_m"], discs["points"][:, :2]
            if len(radius) == 0:
                fail("%s: %s holds no disc" % (folder, series[1][t]))
            fluid = particles["kind"] == 0
            xy, pressure = particles["points"][fluid, :2], particles["pressure_pa"][fluid].astype(float)
            in_tension += int((pressure < 0).sum())
            particles_read += len(pressure)
            lowest_pa = min(lowest_pa, float(pressure.min(initial=math.inf)))
            column = np.floor(xy[:, 0] / LIFT_COLUMN_M).astype(int)
            column -= column.min()
            top = np.full(column.max() + 1, -np.inf)
            np.maximum.at(top, column, xy[:, 1])
            depth = top[column] - xy[:, 1]
            local_top = np.array([xy[np.abs(xy[:, 0] - c[0]) < r + 2 * dp, 1].max(initial=-np.inf)
                                  for c, r in zip(centre, radius)])
            buoyancies.append(rho * g_normal * submerged_area(radius, local_top + 0.5 * dp - (centre[:, 1] - radius)).sum())
            lifts.append(float(discs["fluid_force_npm"][:, 1].sum()))
            face_gap = (np.hypot(xy[:, None, 0] - centre[None, :, 0], xy[:, None, 1] - centre[None, :, 1])
                        - radius[None, :]).min(axis=1) / dp
            deep = depth > LIFT_DEEP_DP * dp
            for band, low, high in LIFT_BANDS_DP:
                inside = deep & (face_gap >= low) & (face_gap < high)
                sums[band][0] += pressure[inside].sum()
                sums[band][1] += rho * g_normal * depth[inside].sum()
    except (ParamsError, vtp.VtpError) as e:
        fail(str(e))
    if not lifts:
        fail("%s: no disc snapshot within %g-%g s carries the fluid's forces" % (folder, start, stop))
    ratios = {band: (p_sum / h_sum if h_sum > 0 else math.nan) for band, (p_sum, h_sum) in sums.items()}
    return (len(lifts), len(radius), float(np.mean(lifts)), float(np.mean(buoyancies)), ratios,
            in_tension / max(particles_read, 1), lowest_pa)


def command_lift(args):
    bands = [band for band, _, _ in LIFT_BANDS_DP]
    rows = [(folder,) + lift(folder, args.window[0], args.window[1]) for folder in args.folders]
    print("run, snapshots, discs, fluid_lift_npm, submerged_buoyancy_npm, lift_share, "
          + ", ".join("pressure_ratio_" + b for b in bands) + ", fluid_in_tension_share, lowest_pressure_pa")
    for folder, n, discs, fluid_lift, buoyancy, ratios, tension_share, lowest_pa in rows:
        print("%s, %d, %d, %.1f, %.1f, %.3f, %s, %.3f, %.0f" % (folder, n, discs, fluid_lift, buoyancy,
                                                               fluid_lift / buoyancy,
                                                               ", ".join("%.3f" % ratios[b] for b in bands),
                                                               tension_share, lowest_pa))
    return 0


def from_wall_m(params, x):
    """The distance downstream of the upstream wall's face, around the period when the domain is periodic (as
    flow.csv's)."""
    d = x - params.real("walls", "upstream_x_m")
    if params.flag("domain", "periodic_x"):
        period = params.positive("domain", "length_m")
        d = d - period * np.floor(d / period)
    return d


def shape(folder, start, stop, body):
    """(snapshots, column width m, mean surface height per column m, body (start, end) m, mean height over the body
    m, mean front m (nan without flow.csv rows in the window), mean disc distance from the wall m, mean disc centre
    height m (nan without disc snapshots)): see `shape` in the module's text."""
    try:
        p = RunParams(folder)
        dp, column_m = p.positive("numerics", "dp_m"), p.positive("output", "flow_column_m")
        ignore_m, length_m = p.real("output", "flow_ignore_m"), p.positive("domain", "length_m")
        body = body or (ignore_m, ignore_m + 5.0)
        path = os.path.join(folder, "run.pvd")
        if not os.path.isfile(path):
            fail("%s: no run.pvd (shape reads the particle snapshots)" % folder)
        snapshots = [(t, f) for t, f in vtp.read_pvd(path) if start <= t <= stop + 1e-9]
        if not snapshots:
            fail("%s: no particle snapshot within %g-%g s" % (folder, start, stop))
        disc_path = os.path.join(folder, "boulders.pvd")
        disc_files = dict(vtp.read_pvd(disc_path)) if os.path.isfile(disc_path) else {}
        columns = int(math.ceil(length_m / column_m))
        heights, disc_from_wall, disc_height = np.zeros(columns), [], []
        for t, name in snapshots:
            particles = vtp.read_vtp(os.path.join(folder, name), required=("kind",), finite=True)
            xy = particles["points"][particles["kind"] == 0, :2]
            distance = from_wall_m(p, xy[:, 0])
            downstream = distance >= 0  # in a closed domain, fluid behind the wall is not the surge's
            column = np.minimum((distance[downstream] / column_m).astype(int), columns - 1)
            top = np.zeros(columns)
            np.maximum.at(top, column, xy[downstream, 1] + 0.5 * dp)
            heights += top / len(snapshots)
            if t in disc_files:
                discs = vtp.read_vtp(os.path.join(folder, disc_files[t]), required=("radius_m",), finite=True)
                disc_from_wall.extend(from_wall_m(p, discs["points"][:, 0]))
                disc_height.extend(discs["points"][:, 1])
    except (ParamsError, vtp.VtpError) as e:
        fail(str(e))
    centres = (np.arange(columns) + 0.5) * column_m
    in_body = (centres >= body[0]) & (centres < body[1])
    if not in_body.any():
        fail("--body %g %g: no column of %g m within it" % (body[0], body[1], column_m))
    fronts = [float(r["front_from_wall_m"]) for r in study.read_rows(
        TOOL, os.path.join(folder, "flow.csv"), {"time_s": float, "front_from_wall_m": float})
        if start <= float(r["time_s"]) <= stop + 1e-9] if os.path.isfile(os.path.join(folder, "flow.csv")) else []
    mean = lambda v: float(np.mean(v)) if len(v) else math.nan
    return (len(snapshots), column_m, heights, body, float(heights[in_body].mean()), mean(fronts),
            mean(disc_from_wall), mean(disc_height))


def command_shape(args):
    rows = [(folder,) + shape(folder, args.window[0], args.window[1], args.body) for folder in args.folders]
    print("run, snapshots, body_from_wall_m, body_height_m, front_from_wall_m, disc_from_wall_m, disc_centre_height_m")
    for folder, n, _, _, body, body_height, front, disc_x, disc_y in rows:
        print("%s, %d, %g-%g, %.3f, %.2f, %.2f, %.3f" % (folder, n, body[0], body[1], body_height, front, disc_x,
                                                         disc_y))
    if args.csv:
        widths = {r[2] for r in rows}
        if len(widths) > 1:
            fail("--csv: the folders' columns differ in width (output.flow_column_m %s)" % sorted(widths))
        longest = max(len(r[3]) for r in rows)
        write_csv(args.csv, [["from_wall_m"] + ["height_m %s" % r[0] for r in rows]]
                  + [["%g" % ((c + 0.5) * rows[0][2])] + ["%.4f" % r[3][c] if c < len(r[3]) else "" for r in rows]
                     for c in range(longest)])
    return 0


def history(folder, start, stop, block_s):
    """[(block start, block end, rows, mean Fr, mean mu_eq/mu0)] of the run's flow.csv over the blocks of block_s
    from start that end by stop and by the run's last row; rows that are not finite are left out."""
    path = os.path.join(folder, "flow.csv")
    if not os.path.isfile(path):
        fail("%s: no flow.csv" % folder)
    rows = [(float(r["time_s"]), float(r["froude"]), float(r["mu_eq_over_mu0"]))
            for r in study.read_rows(TOOL, path, {"time_s": float, "froude": float, "mu_eq_over_mu0": float})]
    end = min(stop, max(t for t, _, _ in rows))
    blocks = []
    for k in range(int(math.floor((end - start) / block_s + 1e-9))):
        low, high = start + k * block_s, start + (k + 1) * block_s
        chosen = [(fr, mu) for t, fr, mu in rows
                  if low - 1e-9 <= t < high - 1e-9 and math.isfinite(fr) and math.isfinite(mu)]
        if chosen:
            blocks.append((low, high, len(chosen), sum(c[0] for c in chosen) / len(chosen),
                           sum(c[1] for c in chosen) / len(chosen)))
    return blocks


HISTORY_MOST_BLOCKS = 100000  # history: more blocks than this is a --block-s typed wrong (0.0005 s over 75 s)


def command_history(args):
    if (args.window[1] - args.window[0]) / args.block_s > HISTORY_MOST_BLOCKS:
        fail("--block-s %g: %g s of window would make more than %d blocks"
             % (args.block_s, args.window[1] - args.window[0], HISTORY_MOST_BLOCKS))
    runs = [(folder, {b[0]: b for b in history(folder, args.window[0], args.window[1], args.block_s)})
            for folder in args.folders]
    starts = sorted({s for _, blocks in runs for s in blocks})
    if not starts:
        fail("--window %g %g: no block of %g s fits in any run's flow.csv" % (args.window[0], args.window[1],
                                                                           args.block_s))
    names = [os.path.join(os.path.basename(os.path.dirname(os.path.abspath(f))), os.path.basename(os.path.abspath(f)))
             for f, _ in runs]
    print("block (s), then per run: Fr, mu_eq/mu0 (rows)  [%s]" % "; ".join(names))
    table = []
    for s in starts:
        cells = [blocks.get(s) for _, blocks in runs]
        high = next(c[1] for c in cells if c)
        table.append((s, high, cells))
        print("%7.2f-%-7.2f " % (s, high) + "  ".join("%6.3f %6.3f (%d)" % (c[3], c[4], c[2]) if c else "%17s" % "-"
                                                      for c in cells))
    if args.csv:
        write_csv(args.csv, [["block_start_s", "block_end_s"]
                             + [h for n in names for h in ("froude %s" % n, "mu_eq_over_mu0 %s" % n)]]
                  + [["%g" % s, "%g" % high]
                     + [v for c in cells for v in (("%.4f" % c[3], "%.4f" % c[4]) if c else ("", ""))]
                     for s, high, cells in table], lineterminator="\n")
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
        for k, name in enumerate(names):
            xs = [[s, high] for s, high, cells in table if cells[k]]
            for ax, column in ((axes[0], 3), (axes[1], 4)):
                ys = [cells[k][column] for _, _, cells in table if cells[k]]
                ax.plot([x for pair in xs for x in pair], [y for y in ys for _ in range(2)], color="C%d" % k,
                        label=name)
        axes[0].set_ylabel("Fr")
        axes[1].set_ylabel("mu_eq / mu0")
        axes[1].set_xlabel("time (s)")
        axes[0].legend(fontsize=8)
        fig.suptitle("debris surge: means over %g s blocks (flow.csv)" % args.block_s)
        fig.tight_layout()
        fig.savefig(args.png, dpi=100)
        print("%s: wrote %s" % (TOOL, args.png))
    return 0


def largest_density_deviation(folder):
    """The largest |rho/rho0 - 1| of the fluid over the run, as diagnostics.csv sampled it (its rows, every
    output.diagnostics_interval_s); nan without the file."""
    path = os.path.join(folder, "diagnostics.csv")
    if not os.path.isfile(path):
        return float("nan")
    return max(float(r["max_density_deviation"])
               for r in study.read_rows(TOOL, path, {"max_density_deviation": float}))


def solid_fraction(folder):
    """(disc area (boulders.csv) over the initial fluid block's area (params.ini), discs); (0, 0) without discs."""
    path = os.path.join(folder, "boulders.csv")
    if not os.path.isfile(path):
        return 0.0, 0
    try:
        p = RunParams(folder)
        block = (p.real("fluid", "x1_m") - p.real("fluid", "x0_m")) * p.positive("fluid", "depth_m")
    except ParamsError as e:
        fail(str(e))
    rows = study.read_rows(TOOL, path, {"r_m": float})
    return sum(math.pi * float(r["r_m"]) ** 2 for r in rows) / block, len(rows)


def run_dp(folder):
    """The dp the member ran with, from its params.ini: a dp that does not divide the period is moved by surge
    (apps/surge/case_loading.c, fit_dp_to_period), so the folder's name holds the requested dp, not always the one run."""
    try:
        return RunParams(folder).positive("numerics", "dp_m")
    except ParamsError as e:
        fail(str(e))


def uniform_froude(folder):
    """Fr of the uniform flow at the belt speed, from the member's params.ini: depth h_n = sqrt(3 nu u_b / (g sin
    theta)), Fr = u_b / sqrt(g h_n); its mu_eq/mu0 is 1 by eq. 21."""
    try:
        p = RunParams(folder)
        nu, g = p.positive("fluid", "viscosity_m2ps"), p.positive("body", "gravity_mps2")
        u_b, theta = abs(p.real("walls", "bottom_speed_mps")), math.radians(p.real("body", "slope_deg"))
    except ParamsError as e:
        fail(str(e))
    if u_b <= 0 or math.sin(theta) <= 0:
        return math.nan  # no uniform flow down a flat or rising channel, or without a moving belt
    h_n = math.sqrt(3 * nu * u_b / (g * math.sin(theta)))
    return u_b / math.sqrt(g * h_n)


def command_collect(args):
    if not os.path.isdir(args.runs_dir):
        fail("--runs-dir %s: no such folder" % args.runs_dir)
    table = []
    for name in sorted(os.listdir(args.runs_dir)):
        folder = os.path.join(args.runs_dir, name)
        flow = os.path.join(folder, "flow.csv")
        folder_name = re.fullmatch(r"(n(\d+)|phi(\d+(?:\.\d+)?))_s(\d+)_dp([0-9.e+-]+)", name)
        if not (folder_name and os.path.isfile(flow)):
            continue
        asked, seed = folder_name.group(1), int(folder_name.group(4))
        phi, count = solid_fraction(folder)
        if count == 0 and asked != "n0":
            fail("%s: a member with discs (%s) but no boulders.csv" % (folder, asked))
        dp = run_dp(folder)
        try:
            progress = study.read_progress(folder)
        except ValueError as e:
            fail(str(e))
        start, stop, n_rows, means, end, errors = window_means(flow, args.window)
        on_belt = boulders_on_belt(folder, start, stop)
        table.append({"asked": asked, "count": count, "seed": seed, "dp_m": dp, "phi": phi,
                      "window_start_s": start, "window_end_s": stop, "rows": n_rows, "froude": means["froude"],
                      "froude_se": errors["froude"], "mu_eq_over_mu0": means["mu_eq_over_mu0"],
                      "mu_eq_over_mu0_se": errors["mu_eq_over_mu0"], "h_max_m": means["h_max_m"],
                      "u_bar_mps": means["u_bar_mps"], "boulders_behind_front_m": means["boulders_behind_front_m"],
                      "boulders_on_belt": on_belt[0], "boulders_on_belt_se": on_belt[1], **on_belt[2],
                      **contact_forces(flow, start, stop),
                      "most_boulders_ahead": most_boulders_ahead(flow), "end_s": end, "wall_s": progress["wall_s"],
                      "status": progress["status"], "uniform_froude": uniform_froude(folder),
                      "max_density_deviation": largest_density_deviation(folder)})
    if not table:
        fail("no member with a flow.csv in %s (run the ensemble first)" % args.runs_dir)
    table.sort(key=lambda r: (r["dp_m"], r["asked"][0] == "p", asked_value(r["asked"]), r["seed"]))
    print("%8s %6s %5s %7s %6s %13s %15s %15s %13s %7s %7s %9s" % (
        "asked", "count", "seed", "dp (m)", "phi", "window (s)", "Fr +- se", "mu/mu0 +- se", "on belt", "end (s)",
        "status", "max drho"))
    for r in table:
        print("%8s %6d %5d %7g %6.3f %6.1f-%-6.1f %7.3f +-%5.3f %7.3f +-%5.3f %5.2f +-%5.2f %7.1f %7s %9.4f" % (
            r["asked"], r["count"], r["seed"], r["dp_m"], r["phi"], r["window_start_s"], r["window_end_s"], r["froude"],
            r["froude_se"], r["mu_eq_over_mu0"], r["mu_eq_over_mu0_se"], r["boulders_on_belt"],
            r["boulders_on_belt_se"], r["end_s"], r["status"][:7], r["max_density_deviation"]))
    if args.csv:
        write_csv(args.csv, [COLUMNS] + [[r.get(c, "") for c in COLUMNS] for r in table])
    if args.png:
        box_plots(table, args.png, "the members of %s" % args.runs_dir)
    return 0


def command_plot(args):
    """Box plots from tables that collect wrote (or made by hand with the same columns)."""
    table, where = [], {}
    for path in args.csv:
        for line, r in study.read_numbered_rows(TOOL, path, PLOTTED):
            row = {k: kind(r[k]) for k, kind in PLOTTED.items()}
            place = "%s, line %d" % (path, line)
            for k, (low, high) in PLOTTED_RANGES.items():
                if not (low < row[k] < high or (k in ZERO_ALLOWED and row[k] == low)):
                    fail("%s: %s = %s is %s" % (place, k, r[k], "not a finite number" if not math.isfinite(row[k])
                                                else "outside %s%g, %g)" % ("[" if k in ZERO_ALLOWED else "(",
                                                                              low, high)))
            if not re.fullmatch(r"n\d+|phi\d+(\.\d+)?", row["asked"]):
                fail("%s: asked = %r is neither n<count> nor phi<fraction>" % (place, row["asked"]))
            if row["window_end_s"] <= row["window_start_s"]:
                fail("%s: the window %s-%s s is empty" % (place, r["window_start_s"], r["window_end_s"]))
            member = (row["dp_m"], row["asked"], row["seed"])
            if member in where:
                fail("%s: dp %g m, %s, seed %d again (first at %s): a member counted twice"
                     % (place, row["dp_m"], row["asked"], row["seed"], where[member]))
            where[member] = place
            first = table[0] if table else row
            if any(abs(row[k] - first[k]) > args.window_tolerance_s for k in ("window_start_s", "window_end_s")):
                fail("%s: its window %g-%g s is not the first row's, %g-%g s (%s), within %g s: members averaged "
                     "over other windows are not comparable (--window-tolerance-s)"
                     % (place, row["window_start_s"], row["window_end_s"], first["window_start_s"],
                        first["window_end_s"], where[(first["dp_m"], first["asked"], first["seed"])],
                        args.window_tolerance_s))
            table.append(row)
    box_plots(table, args.png, ", ".join(args.csv))
    return 0


def compared_table(path, tolerance_s, first):
    """compare's rows of one table by (asked, seed), vetted; first: a row of the first table for its window."""
    rows = {}
    for line, r in study.read_numbered_rows(TOOL, path, COMPARED):
        row = {k: kind(r[k]) for k, kind in COMPARED.items()}
        place = "%s, line %d" % (path, line)
        for k in ("froude", "mu_eq_over_mu0", "dp_m"):
            if not (math.isfinite(row[k]) and row[k] > 0):
                fail("%s: %s = %s is not a positive number" % (place, k, r[k]))
        for k in ("froude_se", "mu_eq_over_mu0_se"):
            if not (math.isnan(row[k]) or row[k] >= 0) or math.isinf(row[k]):
                fail("%s: %s = %s is neither a standard error nor nan" % (place, k, r[k]))
        if not re.fullmatch(r"n\d+|phi\d+(\.\d+)?", row["asked"]):
            fail("%s: asked = %r is neither n<count> nor phi<fraction>" % (place, row["asked"]))
        key = (row["asked"], row["seed"])
        if key in rows:
            fail("%s: %s seed %d again (first at line %d): a member counted twice" % (place, key[0], key[1],
                                                                                      rows[key]["line"]))
        reference = first or row
        if any(abs(row[k] - reference[k]) > tolerance_s for k in ("window_start_s", "window_end_s")):
            fail("%s: its window %g-%g s is not %g-%g s (the first table's first row) within %g s: means over other "
                 "windows are not comparable (--window-tolerance-s)"
                 % (place, row["window_start_s"], row["window_end_s"], reference["window_start_s"],
                    reference["window_end_s"], tolerance_s))
        rows[key] = dict(row, line=line)
    return rows


def member_order(key):
    """compare's order of (asked, seed): the counts, then the solid fractions, each by value, then the seed"""
    return key[0][0] == "p", asked_value(key[0]), key[1]


def against(a, a_se, b, b_se):
    """B against A: the relative difference in percent and in units of the two errors combined (nan without)."""
    combined = math.hypot(a_se, b_se)
    return 100.0 * (b / a - 1.0), ((b - a) / combined if combined > 0 else float("nan"))


def command_compare(args):
    """Two collect tables member by member, and their means over the members both have."""
    if len(args.csv) != 2:
        fail("compare takes two tables (--csv A --csv B), got %d" % len(args.csv))
    first = compared_table(args.csv[0], args.window_tolerance_s, None)
    reference = next(iter(first.values()))
    second = compared_table(args.csv[1], args.window_tolerance_s, reference)
    both = sorted(set(first) & set(second), key=member_order)
    if not both:
        fail("no member is in both %s and %s (members match by asked and seed)" % tuple(args.csv))
    print("A = %s\nB = %s\nwindow %g-%g s" % (args.csv[0], args.csv[1], reference["window_start_s"],
                                               reference["window_end_s"]))
    header = "%8s %5s %7s %7s %17s %17s %17s %17s %17s %17s" % (
        "asked", "seed", "dp A", "dp B", "Fr A", "Fr B", "B vs A (errors)", "mu/mu0 A", "mu/mu0 B", "B vs A (errors)")
    print(header)
    pair = "%8.3f +-%6.3f %8.3f +-%6.3f %+8.1f %% (%+5.1f)"
    line = "%8s %5s %7s %7s " + pair + " " + pair
    values = {k: ([], []) for k in ("froude", "mu_eq_over_mu0")}
    for key in both:
        a, b = first[key], second[key]
        cells = []
        for k in ("froude", "mu_eq_over_mu0"):
            values[k][0].append(a[k])
            values[k][1].append(b[k])
            cells += [a[k], a[k + "_se"], b[k], b[k + "_se"], *against(a[k], a[k + "_se"], b[k], b[k + "_se"])]
        print(line % (key[0], key[1], "%g" % a["dp_m"], "%g" % b["dp_m"], *cells))
    cells = []
    for k in ("froude", "mu_eq_over_mu0"):
        means, errors = [], []
        for v in values[k]:
            means.append(float(np.mean(v)))
            errors.append(float(np.std(v, ddof=1) / math.sqrt(len(v))) if len(v) > 1 else float("nan"))
        cells += [means[0], errors[0], means[1], errors[1], *against(means[0], errors[0], means[1], errors[1])]
    print(line % ("mean", "of %d" % len(both), "", "", *cells))
    for path, table, other in ((args.csv[0], first, second), (args.csv[1], second, first)):
        alone = sorted(set(table) - set(other), key=member_order)
        if alone:
            print("only in %s: %s" % (path, ", ".join("%s seed %d" % k for k in alone)))
    return 0


def asked_value(asked):
    """the number in a member's n<count> or phi<solid fraction>"""
    return float(asked[1:] if asked.startswith("n") else asked[3:])


def box_plots(table, png, source):
    """Fr and mu_eq/mu0 against phi, one box per (dp, asked) group, with the uniform flow's values (mu_eq/mu0 = 1
    by eq. 21) as the phi = 0 reference: every row must give the same uniform Fr (the same scene)."""
    references = [r["uniform_froude"] for r in table]
    if not all(math.isfinite(f) for f in references):
        fail("%s: a member has no uniform flow (uniform_froude nan: a channel without slope or belt), so no reference"
             % source)
    if max(references) > 1.001 * min(references):
        fail("%s: the rows come from scenes with different uniform flows (Fr %g to %g)"
             % (source, min(references), max(references)))
    fr_uniform, mu_uniform = sum(references) / len(references), 1.0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    groups = {}
    for r in table:
        groups.setdefault((r["dp_m"], r["asked"]), []).append(r)
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, key, label, reference in ((axes[0], "froude", "Fr", fr_uniform),
                                      (axes[1], "mu_eq_over_mu0", "mu_eq / mu0", mu_uniform)):
        positions, data, means = [], [], []
        for (dp, asked), rows in sorted(groups.items(), key=lambda g: (g[0][0], g[1][0]["phi"])):
            positions.append(sum(r["phi"] for r in rows) / len(rows))
            data.append([r[key] for r in rows])
            means.append(sum(data[-1]) / len(data[-1]))
        ax.boxplot(data, positions=positions, widths=0.04, whis=(0, 100), manage_ticks=False)
        ax.plot(positions, means, "o", color="C1", label="mean over seeds")
        ax.axhline(reference, ls="--", color="grey", label="uniform flow, phi = 0")
        low, high = ax.get_ylim()  # the reference line in view even where every box lies on one side of it
        margin = 0.05 * (max(high, reference) - min(low, reference))
        ax.set_ylim(min(low, reference - margin), max(high, reference + margin))
        ax.set_xlabel("solid fraction phi")
        ax.set_ylabel(label)
        ax.set_xlim(-0.05, max(positions) + 0.1)
        ax.legend(fontsize=8)
    dps = sorted({r["dp_m"] for r in table})
    windows = sorted({"%.4g-%.4g s" % (r["window_start_s"], r["window_end_s"]) for r in table})
    fig.suptitle("debris surge ensemble (dp %s m; %s %s; boxes: quartiles, whiskers: extremes)"
                 % (", ".join("%g" % d for d in dps), "window" if len(windows) == 1 else "windows",
                    ", ".join(windows)))
    fig.tight_layout()
    fig.savefig(png, dpi=100)
    print("%s: wrote %s" % (TOOL, png))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    for name in ("run", "list"):
        p = sub.add_parser(name, help="run the members" if name == "run" else
                           "print the members, one a line: index, discs (or phi<fraction>), seed, folder")
        p.add_argument("--counts", type=counts_list, default=None,
                       help="disc counts, comma-separated (default: the paper's 0,50,100,154, or none with --phis)")
        p.add_argument("--phis", type=phis_list, default=[],
                       help="solid fractions, comma-separated: members with graded discs covering that fraction of the "
                            "fluid block's area, as near as the sizes drawn allow, after the counts' (default none)")
        p.add_argument("--seeds", type=cli_checks.positive_int, default=5,
                       help="seeds 1..N per disc count or solid fraction (count 0 runs once; default 5)")
        p.add_argument("--dp", type=cli_checks.positive, default=0.05, help="particle spacing, m (default 0.05)")
        p.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "debris_surge"),
                       help="where the member folders go (default runs/debris_surge)")
        if name == "run":
            p.add_argument("--end-s", type=cli_checks.positive, default=75.0,
                           help="seconds of flow per member (default the paper's 75)")
            p.add_argument("--threads", type=cli_checks.positive_int, default=1, help="threads per member (default 1)")
            p.add_argument("--jobs", type=cli_checks.positive_int, default=1,
                           help="members run at a time (default 1)")
            p.add_argument("--member", type=int, default=None,
                           help="run only this member of `list` (0-based; a job array's index)")
            p.add_argument("--budget-s", type=cli_checks.non_negative, default=0.0,
                           help="wall time, s, after which running members stop at a checkpoint and no more start; "
                                "run again to resume (0: none)")
            p.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"),
                           help="the surge program (default build/surge)")
            p.add_argument("--set", action="append", default=[], type=setting_arg, metavar="NAME=VALUE",
                           help="a parameter for every member, repeatable (vetted by surge check)")
            p.add_argument("--continue-stopped", action="store_true",
                           help="continue members the health monitor stopped from their last good state, with the "
                                "--set parameters (live ones only, e.g. health.max_density_deviation=0.2)")
            p.add_argument("--parked-dir", type=cli_checks.folder, default=PARKED_DIR,
                           help="where a member that finishes deletes its parked copy (default "
                                "studies/debris_surge/parked)")
    for name in ("park", "unpark"):
        p = sub.add_parser(name, help="carry unfinished members to the next checkout" if name == "park" else
                           "restore parked members into --runs-dir")
        p.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "debris_surge"),
                       help="the members' folders (default runs/debris_surge)")
        p.add_argument("--parked-dir", type=cli_checks.folder, default=PARKED_DIR,
                       help="the parked members (default studies/debris_surge/parked, committed)")
    c = sub.add_parser("collect", help="the members' statistics: table and box plots")
    c.add_argument("--runs-dir", default=os.path.join(ROOT, "runs", "debris_surge"),
                   help="the members' folders (default runs/debris_surge)")
    c.add_argument("--window", type=cli_checks.non_negative, nargs=2, default=[20.0, 75.0],
                   metavar=("START_S", "END_S"),
                   help="the averaging window, s of flow (default the paper's 20 75)")
    c.add_argument("--csv", type=cli_checks.output_file, help="write the table to this CSV file")
    c.add_argument("--png", type=cli_checks.png_file, help="draw the box plots to this PNG file")
    d = sub.add_parser("plot", help="box plots from tables that collect wrote")
    d.add_argument("--csv", action="append", required=True, metavar="FILE",
                   help="a table collect wrote (--csv), or one with its "
                        "columns %s; repeatable"
                        % ", ".join(PLOTTED))
    d.add_argument("--png", type=cli_checks.png_file, required=True, help="draw the box plots to this PNG file")
    d.add_argument("--window-tolerance-s", type=cli_checks.non_negative, default=WINDOW_TOLERANCE_S,
                   help="how far, s, a row's averaging window may lie from the first row's (default %g: one flow "
                        "row); the title lists the windows" % WINDOW_TOLERANCE_S)
    e = sub.add_parser("compare", help="two tables that collect wrote, member by member (schemes, resolutions)")
    e.add_argument("--csv", action="append", required=True, metavar="FILE",
                   help="a table collect wrote; twice: A, then B, which is read against A")
    e.add_argument("--window-tolerance-s", type=cli_checks.non_negative, default=WINDOW_TOLERANCE_S,
                   help="how far, s, a row's averaging window may lie from A's first row's (default %g)"
                        % WINDOW_TOLERANCE_S)
    f = sub.add_parser("lift", help="how much of their buoyancy the fluid gives the discs, from the snapshots")
    f.add_argument("folders", nargs="+", type=cli_checks.folder, metavar="RUN_DIR",
                   help="run folders with particle (run.pvd) and disc (boulders.pvd) snapshots")
    f.add_argument("--window", type=cli_checks.non_negative, nargs=2, default=[6.0, 20.0],
                   metavar=("START_S", "END_S"), help="the snapshots' window, s of flow (default 6 20)")
    h = sub.add_parser("shape", help="the surge's mean surface profile, front and disc positions, from the snapshots")
    h.add_argument("folders", nargs="+", type=cli_checks.folder, metavar="RUN_DIR",
                   help="run folders with particle snapshots (run.pvd)")
    h.add_argument("--window", type=cli_checks.non_negative, nargs=2, default=[6.0, 20.0],
                   metavar=("START_S", "END_S"), help="the snapshots' window, s of flow (default 6 20)")
    h.add_argument("--body", type=cli_checks.non_negative, nargs=2, default=None, metavar=("START_M", "END_M"),
                   help="where the body's mean height is taken, m downstream of the wall's face (default the 5 m "
                        "after output.flow_ignore_m)")
    h.add_argument("--csv", type=cli_checks.output_file, help="write the mean profiles to this CSV file, one column per folder")
    g = sub.add_parser("history", help="Fr and mu_eq/mu0 over consecutive blocks of time, run by run (flow.csv)")
    g.add_argument("folders", nargs="+", type=cli_checks.folder, metavar="RUN_DIR", help="run folders with flow.csv")
    g.add_argument("--window", type=cli_checks.non_negative, nargs=2, default=[0.0, 75.0],
                   metavar=("START_S", "END_S"), help="the blocks' span, s of flow (default 0 75)")
    g.add_argument("--block-s", type=cli_checks.positive, default=2.0, help="each block's length, s (default 2)")
    g.add_argument("--csv", type=cli_checks.output_file, help="write the blocks' means to this CSV file, two columns per folder")
    g.add_argument("--png", type=cli_checks.png_file, help="draw them against time to this PNG file")
    args = parser.parse_args()
    if args.command in ("run", "list") and args.counts is None:
        args.counts = [] if args.phis else [0, 50, 100, 154]
    if args.command == "list":
        for k, (asked, seed) in enumerate(members(args)):
            print("%d %s %d %s" % (k, asked[1] if asked[0] == "n" else asked_name(asked), seed,
                                   folder_of(args, asked, seed)))
        return 0
    if args.command == "park":
        return study.park_command(TOOL, args.runs_dir, args.parked_dir, PARKED_EXTRA, first_snapshot=False)
    if args.command == "unpark":
        return study.unpark_command(TOOL, args.parked_dir, args.runs_dir)
    if args.command in ("collect", "lift", "shape", "history") and not args.window[1] > args.window[0]:
        fail("--window: the end must come after the start")
    if args.command == "shape" and args.body and not args.body[1] > args.body[0]:
        fail("--body: the end must come after the start")
    if args.command == "plot":
        return command_plot(args)
    if args.command == "compare":
        return command_compare(args)
    if args.command == "lift":
        return command_lift(args)
    if args.command == "shape":
        return command_shape(args)
    if args.command == "history":
        return command_history(args)
    return command_run(args) if args.command == "run" else command_collect(args)


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
