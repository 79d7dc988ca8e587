"""Helpers shared by the study drivers (freydier_convergence.py, stability_map.py, poiseuille_loaded.py): option
parsing, errors, resumable runs and the append-only CSV tables they write."""
import csv
import json
import os
import signal
import subprocess
import sys
import time

from run_params import RunParams


def fail(program, message):
    """One-line error on stderr, exit status 2 (bad input)."""
    print("%s: %s" % (program, message), file=sys.stderr)
    sys.exit(2)


def positive_numbers(program, text, option):
    """Comma-separated positive numbers of --option, or a clear error."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        fail(program, "--%s: expected comma-separated numbers, got '%s'" % (option, text))
    if not values or any(v <= 0 for v in values):
        fail(program, "--%s: expected positive numbers, got '%s'" % (option, text))
    return values


def check_columns(program, csv_path, columns):
    """An existing table must have this tool's columns, in order (checked before a study starts, so that a long run
    does not end on a table it cannot extend)."""
    if not os.path.isfile(csv_path):
        return
    with open(csv_path, newline="") as f:
        header = next(csv.reader(f), [])
    if header != list(columns):
        fail(program, "%s: its columns (%s) are not this tool's (%s)" % (csv_path, ",".join(header),
                                                                         ",".join(columns)))


def append_row(csv_path, columns, row):
    """Appends row to the CSV table, writing the header when the file is new."""
    new = not os.path.isfile(csv_path)
    os.makedirs(os.path.dirname(os.path.abspath(csv_path)), exist_ok=True)
    with open(csv_path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        if new:
            writer.writeheader()
        writer.writerow(row)


def solver_environment():
    """The environment for surge runs: idle OpenMP threads sleep instead of spinning (OMP_WAIT_POLICY=PASSIVE,
    unless set), so a run sharing its cores with other work does not slow down several-fold."""
    env = dict(os.environ)
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    return env


def read_progress(folder):
    """progress.json of a run folder: wall seconds summed over its pieces and its status."""
    try:
        with open(os.path.join(folder, "progress.json")) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {"wall_s": 0.0, "status": "new"}


def write_progress(folder, progress):
    with open(os.path.join(folder, "progress.json"), "w") as f:
        json.dump(progress, f, indent=1)


def run_resumable(tool, folder, fresh_argv, surge, common, deadline):
    """Runs surge for one study point in folder: from its checkpoint when an earlier piece was interrupted, else
    fresh_argv (which names the case and -o folder; the run starts over); common options go to both. At the deadline (wall clock,
    None: none) or on Ctrl-C the run gets SIGINT and leaves a checkpoint (exit 4). Returns (exit status,
    progress) with the wall time of all pieces in progress["wall_s"]; the caller records the final status."""
    os.makedirs(folder, exist_ok=True)
    progress = read_progress(folder)
    checkpoint = os.path.join(folder, "checkpoint.bin")
    if os.path.isfile(checkpoint) and progress["status"] in ("interrupted", "running"):
        argv = [surge, "run", "--restart", checkpoint] + common
    else:
        argv = fresh_argv + common
        progress["wall_s"] = 0.0  # a fresh start (after a failed run, say) owes nothing to earlier pieces
    print("%s: %s" % (tool, " ".join(argv)), flush=True)
    progress["status"] = "running"
    write_progress(folder, progress)
    start = time.time()
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, env=solver_environment())
    try:
        while proc.poll() is None:
            if deadline and time.time() > deadline:
                proc.send_signal(signal.SIGINT)
                proc.wait()
                break
            time.sleep(1)
    except KeyboardInterrupt:
        proc.send_signal(signal.SIGINT)
        proc.wait()
    progress["wall_s"] += time.time() - start
    if proc.returncode == 4:
        progress["status"] = "interrupted"
    write_progress(folder, progress)
    return proc.returncode, progress


def particle_steps(folder):
    """Fluid particles (params.ini header) x steps (last diagnostics row), and the final simulated time."""
    fluid = int(RunParams(folder).derived("fluid particles"))
    with open(os.path.join(folder, "diagnostics.csv")) as f:
        rows = list(csv.reader(f))
    last = rows[-1]
    return fluid * int(last[1]), float(last[0])


def read_rows(tool, csv_path):
    """The rows of a study's CSV table; fails with a message naming the file when it is missing or empty."""
    if not os.path.isfile(csv_path):
        fail(tool, "%s: no such file" % csv_path)
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(tool, "%s: no rows" % csv_path)
    return rows
