"""Helpers shared by the study drivers (freydier_convergence.py, stability_map.py, poiseuille_loaded.py): option
parsing, errors, resumable runs and the append-only CSV tables they write."""
import csv
import gzip
import json
import os
import shutil
import signal
import struct
import subprocess
import sys
import time

import vtp
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
    start = time.time()
    progress["status"] = "running"
    progress["piece_started_unix"] = start  # lets park() count a running piece's time up to its last checkpoint
    write_progress(folder, progress)
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
    del progress["piece_started_unix"]
    if proc.returncode == 4:
        progress["status"] = "interrupted"
    write_progress(folder, progress)
    return proc.returncode, progress


PARKED_FILES = ("checkpoint.bin", "progress.json", "params.ini", "diagnostics.csv", "run.pvd", "boulders.pvd",
                "control.jsonl")


def checkpoint_time(path):
    """(step, simulated time in s) recorded in a checkpoint's header (layout in sim/src/checkpoint.c)."""
    with open(path, "rb") as f:
        head = f.read(24)
        if len(head) < 24 or head[:8] != b"SURGECK1":
            raise ValueError("%s: not a surge checkpoint" % path)
        f.seek(24 + struct.unpack("<Q", head[16:24])[0])
        step, time_s = struct.unpack("<qd", f.read(16))
    return step, time_s


def _first_snapshot(folder):
    """The first snapshot listed in the folder's run.pvd (the initial state, which the metrics read), or None."""
    try:
        entries = vtp.read_pvd(os.path.join(folder, "run.pvd"))
    except (OSError, ValueError, vtp.ET.ParseError):
        return None
    return entries[0][1] if entries else None


def park(tool, runs_dir, parked_dir):
    """Copies every unfinished run of runs_dir into parked_dir/NAME: its checkpoint, its small files and its first
    snapshot, the large ones gzip-compressed. Only the committed tree survives from one session to the next; a parked
    run is carried in it and resumed by unpark in a fresh checkout. A run still going is parked at its last periodic
    checkpoint (written atomically), with the wall time of its current piece counted up to that checkpoint. Returns
    the names parked."""
    parked = []
    for name in sorted(os.listdir(runs_dir)) if os.path.isdir(runs_dir) else []:
        folder = os.path.join(runs_dir, name)
        checkpoint = os.path.join(folder, "checkpoint.bin")
        progress = read_progress(folder)
        if progress["status"] not in ("interrupted", "running") or not os.path.isfile(checkpoint):
            continue
        if progress["status"] == "running":
            started = progress.pop("piece_started_unix", None)
            if started is None or os.path.getmtime(checkpoint) < started:
                continue  # no checkpoint of this piece yet (or a piece of unknown start): nothing safe to park
            progress["wall_s"] += os.path.getmtime(checkpoint) - started
            progress["status"] = "interrupted"
        target = os.path.join(parked_dir, name)
        shutil.rmtree(target, ignore_errors=True)
        os.makedirs(target)
        first = _first_snapshot(folder)
        for f in PARKED_FILES + ((first,) if first else ()):
            source = os.path.join(folder, f)
            if not os.path.isfile(source):
                continue
            if f == "progress.json":
                with open(os.path.join(target, f), "w") as out:
                    json.dump(progress, out, indent=1)
            elif f.endswith((".bin", ".vtp")):
                with open(source, "rb") as src, gzip.GzipFile(os.path.join(target, f + ".gz"), "wb", mtime=0) as dst:
                    shutil.copyfileobj(src, dst)
            else:
                shutil.copyfile(source, os.path.join(target, f))
        parked.append(name)
        print("%s: parked %s at its checkpoint of t = %.3f s (step %d) in %s"
              % (tool, name, checkpoint_time(checkpoint)[1], checkpoint_time(checkpoint)[0], target), flush=True)
    return parked


def unpark(tool, parked_dir, runs_dir):
    """Restores each parked run into runs_dir/NAME unless that folder already holds a run (which is newer or
    finished); the next `run` then continues it from its checkpoint. Returns the names restored."""
    restored = []
    for name in sorted(os.listdir(parked_dir)) if os.path.isdir(parked_dir) else []:
        source = os.path.join(parked_dir, name)
        folder = os.path.join(runs_dir, name)
        if not os.path.isfile(os.path.join(source, "progress.json")):
            continue  # not a parked run (a README, or another study's parked folder)
        if os.path.isfile(os.path.join(folder, "progress.json")):
            print("%s: %s already holds a run; left as it is" % (tool, folder), flush=True)
            continue
        os.makedirs(folder, exist_ok=True)
        for f in os.listdir(source):
            if f.endswith(".gz"):
                with gzip.open(os.path.join(source, f), "rb") as src, open(os.path.join(folder, f[:-3]), "wb") as dst:
                    shutil.copyfileobj(src, dst)
            else:
                shutil.copyfile(os.path.join(source, f), os.path.join(folder, f))
        restored.append(name)
        try:
            step, time_s = checkpoint_time(os.path.join(folder, "checkpoint.bin"))
        except (OSError, ValueError, struct.error) as e:
            fail(tool, "parked run %s: %s" % (source, e))
        print("%s: restored %s at its checkpoint of t = %.3f s (step %d)" % (tool, folder, time_s, step), flush=True)
    return restored


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
