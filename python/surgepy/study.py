"""Helpers shared by the study drivers in studies/ (freydier/freydier_convergence.py, stability/stability_map.py,
poiseuille_loaded/poiseuille_loaded.py, debris_surge/ensemble.py): option parsing, errors, resumable runs and the
append-only CSV tables they write."""
import collections
import csv
import gzip
import json
import math
import os
import shutil
import signal
import struct
import subprocess
import sys
import threading
import time
import zlib

from . import vtp
from .cli_checks import fail
from .run_params import ParamsError, RunParams


def positive_numbers(program, text, option):
    """Comma-separated positive numbers of --option, or a clear error."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        fail(program, "--%s: expected comma-separated numbers, got '%s'" % (option, text))
    if not values or any(not 0 < v < math.inf for v in values):
        fail(program, "--%s: expected positive numbers, got '%s'" % (option, text))
    return values


KIND_NAMES = {float: "a number", int: "an integer"}


def _read_table(program, csv_path, types, header=None):
    """The rows of a CSV table as (line, dict) pairs, line being where the row ends; the table must have the columns
    of types ({column: float, int or str}) and in each row a value there that the type reads (float: a number, nan
    included); with header, exactly these columns in this order. Fails naming the file, and the line and column,
    otherwise."""
    try:
        with open(csv_path, newline="") as f:
            reader = csv.DictReader(f)
            columns = reader.fieldnames
            if not columns:
                fail(program, "%s: empty, not a CSV table" % csv_path)
            if header is not None and columns != list(header):
                fail(program, "%s: its columns (%s) are not this tool's (%s)" % (csv_path, ",".join(columns),
                                                                                 ",".join(header)))
            missing = [c for c in types if c not in columns]
            if missing:
                fail(program, "%s: no column %s (its columns: %s)" % (csv_path, ", ".join(missing), ",".join(columns)))
            rows = []
            for row in reader:
                for column, kind in types.items():
                    if row[column] is None:
                        fail(program, "%s, line %d: no %s value (a row shorter than the header)"
                             % (csv_path, reader.line_num, column))
                    try:
                        kind(row[column])
                    except ValueError:
                        fail(program, "%s, line %d: %s = %r is not %s" % (csv_path, reader.line_num, column,
                                                                          row[column], KIND_NAMES[kind]))
                rows.append((reader.line_num, row))
    except OSError as e:
        fail(program, "%s: cannot read it (%s)" % (csv_path, e.strerror or e))
    except (UnicodeDecodeError, csv.Error) as e:
        fail(program, "%s: not a CSV text table (%s)" % (csv_path, e))
    return rows


def read_numbered_rows(program, csv_path, types):
    """The rows of a CSV table with their lines, as (line, dict) pairs (see _read_table); fails with a message naming
    the file when it has none."""
    rows = _read_table(program, csv_path, types)
    if not rows:
        fail(program, "%s: no rows" % csv_path)
    return rows


def read_rows(program, csv_path, types):
    """The rows (dicts) of a CSV table (see read_numbered_rows)."""
    return [row for _, row in read_numbered_rows(program, csv_path, types)]


def existing_rows(program, csv_path, columns, types):
    """The rows of a study's table ([] before it exists), read before the study starts so that a long run does not
    end on a table it cannot extend: it must have this tool's columns, in order, and values of these types."""
    if not os.path.lexists(csv_path):
        return []
    return [row for _, row in _read_table(program, csv_path, types, header=columns)]


def append_row(csv_path, columns, row):
    """Appends row to the CSV table, writing the header when the file is new."""
    new = not os.path.isfile(csv_path)
    os.makedirs(os.path.dirname(os.path.abspath(csv_path)), exist_ok=True)
    with open(csv_path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns, lineterminator="\n")
        if new:
            writer.writeheader()
        writer.writerow(row)


def solver_environment():
    """The environment for surge runs: idle OpenMP threads sleep instead of spinning (OMP_WAIT_POLICY=PASSIVE,
    unless set), so a run sharing its cores with other work does not slow down several-fold."""
    env = dict(os.environ)
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    return env


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def read_progress(folder):
    """progress.json of a run folder: wall seconds summed over its pieces and its status ({"wall_s": 0.0, "status":
    "new"} where there is none). ValueError naming the file when it is not such a JSON object."""
    path = os.path.join(folder, "progress.json")
    try:
        with open(path) as f:
            progress = json.load(f)
    except FileNotFoundError:
        return {"wall_s": 0.0, "status": "new"}
    except (OSError, ValueError) as e:
        raise ValueError("%s: cannot read it (%s)" % (path, e))
    if not (isinstance(progress, dict) and isinstance(progress.get("status"), str)
            and all(_is_number(progress.get(k, 0.0)) for k in ("wall_s", "piece_started_unix"))):
        raise ValueError("%s: not a run's progress (a JSON object with a status, and numbers for wall_s and "
                         "piece_started_unix)" % path)
    progress.setdefault("wall_s", 0.0)
    return progress


def write_progress(folder, progress):
    with open(os.path.join(folder, "progress.json"), "w") as f:
        json.dump(progress, f, indent=1)


def stop_on_surge_error(program, folder, returncode, stderr):
    """Stops the study with surge's own message (the last line of its stderr) when surge refused its input or could
    not write its output (exit 2 or 3) or left no params.ini or diagnostics.csv in folder: the next run would fail
    the same way."""
    missing = [f for f in ("params.ini", "diagnostics.csv") if not os.path.isfile(os.path.join(folder, f))]
    if returncode in (2, 3) or missing:
        lines = [line for line in stderr.splitlines() if line.strip()]
        fail(program, "surge exited with status %d%s: %s" % (
            returncode, "" if returncode in (2, 3) else " and left no %s in %s" % (" or ".join(missing), folder),
            lines[-1] if lines else "(no message)"))


def _echo(stream, tail):
    """Copies surge's stderr to ours as it comes, keeping its last lines in tail."""
    for line in stream:
        sys.stderr.write(line)
        sys.stderr.flush()
        tail.append(line)


def surge_program(surge):
    """The program line of `surge version` ("surge COMMIT, COMPILER, vectors ..."), or None for a surge without that
    command (one older than 2026-11-28) or that cannot be run."""
    try:
        p = subprocess.run([surge, "version"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError):
        return None
    for line in p.stdout.split("\n") if p.returncode == 0 else []:
        if line.startswith("program: "):
            return line[len("program: "):]
    return None


def params_program(folder):
    """The program a run folder's params.ini names (its "# program:" line), or None."""
    try:
        with open(os.path.join(folder, "params.ini")) as f:
            for line in f:
                if line.startswith("# program: "):
                    return line[len("# program: "):].rstrip("\n")
    except OSError:
        pass
    return None


def _record_program(tool, folder, progress, program, resuming):
    """Adds the program of this piece to progress["programs"] (in the order they ran, a program again only after
    another) and, when a run continues under another program than the one it ran last (its progress or, before
    progress recorded it, its params.ini), says so: a checkpoint continues bit for bit only under the same build
    (docs/performance.md). A build from a changed work tree is named by its commit and a hash of the changes
    (tools/build_commit.cmake), so any change, even to docs alone, counts as another program. Where `surge version`
    fails (program None) the piece is not recorded."""
    programs = progress.get("programs")
    if not (isinstance(programs, list) and all(isinstance(p, str) for p in programs)):
        programs = []
    if not resuming:
        programs = []
    elif not programs and params_program(folder):
        programs = [params_program(folder)]
    if program and programs and programs[-1] != program:
        sys.stdout.write("%s: %s: note: it ran under %s and continues under %s; the result is not bit for bit what "
                         "one program would make\n" % (tool, folder, programs[-1], program))
        sys.stdout.flush()
    if program and (not programs or programs[-1] != program):
        programs.append(program)
    progress["programs"] = programs


def run_resumable(tool, folder, fresh_argv, surge, common, deadline, checkpoint_name="checkpoint.bin"):
    """Runs surge for one study point in folder: from its checkpoint (checkpoint_name: last_good.bin continues a run
    the health monitor stopped) when an earlier piece was interrupted, else fresh_argv (which names the case and -o
    folder; the run starts over); common options go to both. At the deadline
    (wall clock, None: none) or on Ctrl-C the run gets SIGINT and leaves a checkpoint (exit 4). Returns (exit status,
    progress) with the wall time of all pieces in progress["wall_s"] and the programs that ran them in
    progress["programs"] (`surge version`; a note when a run continues under another); the caller records the final
    status. Stops the study (exit 2) when surge fails on its input or output (stop_on_surge_error)."""
    os.makedirs(folder, exist_ok=True)
    try:
        progress = read_progress(folder)
    except ValueError as e:
        fail(tool, str(e))
    checkpoint = os.path.join(folder, checkpoint_name)
    resuming = os.path.isfile(checkpoint) and progress["status"] in ("interrupted", "running")
    if resuming:
        argv = [surge, "run", "--restart", checkpoint] + common
    else:
        argv = fresh_argv + common
        progress["wall_s"] = 0.0  # a fresh start (after a failed run, say) owes nothing to earlier pieces
    _record_program(tool, folder, progress, surge_program(surge), resuming)
    sys.stdout.write("%s: %s\n" % (tool, " ".join(argv)))  # one write: members started together print whole lines
    sys.stdout.flush()
    start = time.time()
    progress["status"] = "running"
    progress["piece_started_unix"] = start  # lets park() count a running piece's time up to its last checkpoint
    write_progress(folder, progress)
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, errors="replace",
                            env=solver_environment())
    tail = collections.deque(maxlen=5)
    echo = threading.Thread(target=_echo, args=(proc.stderr, tail), daemon=True)
    echo.start()
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
    echo.join()
    progress["wall_s"] += time.time() - start
    del progress["piece_started_unix"]
    if proc.returncode == 4:
        progress["status"] = "interrupted"
    write_progress(folder, progress)
    if proc.returncode != 4:
        stop_on_surge_error(tool, folder, proc.returncode, "".join(tail))
    return proc.returncode, progress


PARKED_FILES = ("checkpoint.bin", "progress.json", "params.ini", "diagnostics.csv", "run.pvd", "boulders.pvd",
                "control.jsonl")


def checkpoint_time(path):
    """(step, simulated time in s) recorded in a checkpoint's header (layout in sim/src/io/checkpoint.c); ValueError
    naming the file when it is not a surge checkpoint."""
    with open(path, "rb") as f:
        head = f.read(24)
        if len(head) < 24 or head[:8] != b"SURGECK1":
            raise ValueError("%s: not a surge checkpoint" % path)
        offset = 24 + struct.unpack("<Q", head[16:24])[0]
        if offset + 16 > os.fstat(f.fileno()).st_size:
            raise ValueError("%s: a surge checkpoint cut short" % path)
        f.seek(offset)
        step, time_s = struct.unpack("<qd", f.read(16))
    return step, time_s


def _first_snapshot(folder):
    """The first snapshot listed in the folder's run.pvd (the initial state, which the metrics read), or None;
    ValueError when run.pvd names a file outside the folder."""
    try:
        entries = vtp.read_pvd(os.path.join(folder, "run.pvd"))
    except vtp.VtpError:
        return None
    if entries and os.path.basename(entries[0][1]) != entries[0][1]:
        raise ValueError("%s lists %r, not a file of the run folder" % (os.path.join(folder, "run.pvd"), entries[0][1]))
    return entries[0][1] if entries else None


def _names(folder):
    """The entries of a folder (none if it does not exist), less the staging folders of park and unpark."""
    return sorted(n for n in os.listdir(folder) if not n.startswith(".")) if os.path.isdir(folder) else []


def park(tool, runs_dir, parked_dir, extra_files=(), first_snapshot=True):
    """Copies every unfinished run of runs_dir into parked_dir/NAME: its checkpoint, its small files (PARKED_FILES
    and a study's extra_files, such as the debris surge's flow.csv and boulders.csv) and, unless first_snapshot is
    False (a study whose numbers need no snapshot), its first snapshot, the large ones gzip-compressed. Only the
    committed tree survives from one machine or checkout to the next; a parked run is carried in it and resumed by unpark in a
    fresh checkout. A run still going is parked at its last periodic checkpoint (written atomically), with the wall
    time of its current piece counted up to that checkpoint. Returns the names parked. A run that cannot be parked (a bad checkpoint or progress.json) stops it with exit status 2,
    leaving its earlier parked copy, if any, as it was."""
    parked = []
    for name in _names(runs_dir):
        folder = os.path.join(runs_dir, name)
        checkpoint = os.path.join(folder, "checkpoint.bin")
        try:
            progress = read_progress(folder)
        except ValueError as e:
            fail(tool, str(e))
        if progress["status"] not in ("interrupted", "running") or not os.path.isfile(checkpoint):
            continue
        if progress["status"] == "running":
            started = progress.pop("piece_started_unix", None)
            if started is None or os.path.getmtime(checkpoint) < started:
                continue  # no checkpoint of this piece yet (or a piece of unknown start): nothing safe to park
            progress["wall_s"] += os.path.getmtime(checkpoint) - started
            progress["status"] = "interrupted"
        target = os.path.join(parked_dir, name)
        staging = os.path.join(parked_dir, "." + name + ".parking")
        shutil.rmtree(staging, ignore_errors=True)
        try:
            step, time_s = checkpoint_time(checkpoint)
            os.makedirs(staging)
            first = _first_snapshot(folder) if first_snapshot else None
            for f in PARKED_FILES + tuple(extra_files) + ((first,) if first else ()):
                source = os.path.join(folder, f)
                if not os.path.isfile(source):
                    continue
                if f == "progress.json":
                    with open(os.path.join(staging, f), "w") as out:
                        json.dump(progress, out, indent=1)
                elif f.endswith((".bin", ".vtp")):
                    with open(source, "rb") as src, \
                            gzip.GzipFile(os.path.join(staging, f + ".gz"), "wb", mtime=0) as dst:
                        shutil.copyfileobj(src, dst)
                else:
                    shutil.copyfile(source, os.path.join(staging, f))
            shutil.rmtree(target, ignore_errors=True)
            os.rename(staging, target)
        except (OSError, ValueError) as e:
            fail(tool, "cannot park %s: %s" % (folder, e))
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        parked.append(name)
        print("%s: parked %s at its checkpoint of t = %.3f s (step %d) in %s" % (tool, name, time_s, step, target),
              flush=True)
    return parked


def unpark(tool, parked_dir, runs_dir):
    """Restores each parked run into runs_dir/NAME unless that folder already holds a run (which is newer or
    finished); the next `run` then continues it from its checkpoint. Returns the names restored. A parked run that
    cannot be restored (a corrupt file, no valid checkpoint, a folder inside it) stops it with exit status 2, and
    nothing of that run is written into runs_dir."""
    restored = []
    for name in _names(parked_dir):
        source = os.path.join(parked_dir, name)
        folder = os.path.join(runs_dir, name)
        if not os.path.isfile(os.path.join(source, "progress.json")):
            continue  # not a parked run (a README, or another study's parked folder)
        if os.path.isfile(os.path.join(folder, "progress.json")):
            print("%s: %s already holds a run; left as it is" % (tool, folder), flush=True)
            continue
        staging = os.path.join(runs_dir, "." + name + ".unparking")
        shutil.rmtree(staging, ignore_errors=True)
        try:
            read_progress(source)
            os.makedirs(staging)
            for f in os.listdir(source):
                if not os.path.isfile(os.path.join(source, f)):
                    raise ValueError("%s is not a file (a parked run holds files only)" % f)
                if f.endswith(".gz"):
                    try:
                        with gzip.open(os.path.join(source, f), "rb") as src, \
                                open(os.path.join(staging, f[:-3]), "wb") as dst:
                            shutil.copyfileobj(src, dst)
                    except (EOFError, zlib.error, gzip.BadGzipFile) as e:
                        raise ValueError("%s: not a whole gzip file (%s)" % (f, e))
                else:
                    shutil.copyfile(os.path.join(source, f), os.path.join(staging, f))
            try:
                step, time_s = checkpoint_time(os.path.join(staging, "checkpoint.bin"))
            except (OSError, ValueError):
                raise ValueError("no checkpoint.bin.gz holding a surge checkpoint")
            os.makedirs(folder, exist_ok=True)
            for f in os.listdir(staging):
                os.replace(os.path.join(staging, f), os.path.join(folder, f))
        except (OSError, ValueError) as e:
            fail(tool, "parked run %s: %s" % (source, e))
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        restored.append(name)
        print("%s: restored %s at its checkpoint of t = %.3f s (step %d)" % (tool, folder, time_s, step), flush=True)
    return restored


def park_command(tool, runs_dir, parked_dir, extra_files=(), first_snapshot=True):
    """A study's `park` command: park, saying so when there was nothing to park; exit status 0."""
    if not park(tool, runs_dir, parked_dir, extra_files, first_snapshot):
        print("%s: no unfinished run with a checkpoint in %s; nothing parked" % (tool, runs_dir))
    return 0


def unpark_command(tool, parked_dir, runs_dir):
    """A study's `unpark` command: unpark, saying so when nothing was restored; exit status 0."""
    if not unpark(tool, parked_dir, runs_dir):
        print("%s: nothing restored from %s (no parked run there, or each one's folder in %s already holds a run)"
              % (tool, parked_dir, runs_dir))
    return 0


def particle_steps(tool, folder):
    """Fluid particles (params.ini header) x steps (last diagnostics row), and the final simulated time."""
    try:
        fluid = int(RunParams(folder).derived("fluid particles"))
    except ParamsError as e:
        fail(tool, str(e))
    last = read_rows(tool, os.path.join(folder, "diagnostics.csv"), {"time_s": float, "step": int})[-1]
    return fluid * int(last["step"]), float(last["time_s"])


def mean_with_error(values, window_factor=5.0):
    """(mean, standard error of the mean, integrated autocorrelation time in samples) of a time series sampled at a
    fixed interval, such as a run's flow.csv rows over an averaging window. Successive rows of a flow are not
    independent: the error is sd sqrt(tau / n), with tau = 1 + 2 sum_{k=1..M} rho_k (rho_k the autocorrelation at lag
    k) summed to the smallest lag M >= window_factor tau (Sokal's automatic window, as emcee's integrated_time
    takes it) or to n/2 where no lag is that large, and tau at least 1 (a series anticorrelated from one sample to the
    next is not taken as better than independent samples). Fewer than 4 values: the error and tau are nan."""
    n = len(values)
    if n == 0:
        return math.nan, math.nan, math.nan
    mean = sum(values) / n
    if n < 4:
        return mean, math.nan, math.nan
    centred = [v - mean for v in values]
    variance = sum(c * c for c in centred) / n
    if variance == 0:
        return mean, 0.0, 1.0
    tau = 1.0
    for lag in range(1, n // 2 + 1):
        rho = sum(centred[i] * centred[i + lag] for i in range(n - lag)) / (n * variance)
        tau += 2.0 * rho
        if lag >= window_factor * tau:
            break
    tau = max(tau, 1.0)
    sd = math.sqrt(variance * n / (n - 1))
    return mean, sd * math.sqrt(tau / n), tau
