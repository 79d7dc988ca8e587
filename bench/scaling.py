#!/usr/bin/python3
"""scaling: how the solver's speed grows with the thread count, on the scenes users run.

  bench/scaling.py [--bench build/surge-bench] [--max-threads N | --threads 1,T2,...] [--scene NAME,...]
                   [--scheme explicit,implicit] [--quick] [--multigrid-parts N|threads]

For each scene and scheme it runs surge-bench once per thread count, 1, 2, 4, ... up to the machine's physical cores,
or the CPUs this process may use where fewer (or N, the last count also when it is not a power of two; or the counts
--threads lists), and prints
one table, a row per run: the fluid particles, steps, the steps' wall time, the rate in million fluid
particle-steps/s, the speed-up against 1 thread, two estimates of the serial fraction and the phase that took most of
the time. Then, per scene and scheme, each phase's seconds at every thread count and its own speed-up. The phases
are surge-bench's (surge_phase_times in sim/include/surge/sim.h; docs/performance.md, "Where a step's time goes").

- serial: the share of the run's time in the phases that run on one thread, the contact solver, the implicit
  scheme's multigrid builds (on one thread in one hierarchy; with --multigrid-parts the parts are built side by side,
  and the column overstates) and the rest of the step outside the named phases (other). At 1 thread it is Amdahl's
  serial fraction, as far as the phases tell serial work from shared.
- karp-flatt: the serial fraction the measured speed-up S on p threads implies, (1/S - 1/p) / (1 - 1/p). It also
  counts what holds the parallel phases back: waits at their barriers, memory bandwidth, loops a scene is too small
  to share (the implicit scheme keeps its loops on one thread below 10,000 fluid particles), serial loops inside
  them. Where it is far above serial, the loss is in the phases the per-phase tables show not speeding up.

The scenes: film, the benchmark film (cases/incline_film.ini, dp = 5 mm, C_h 1.0, 20,000 fluid particles); film_fine,
the same at dp = 2.5 mm (80,000); debris, the 60-disc debris surge at dp = 0.04 m; freydier, the Freydier ID1 front
at dp = 0.5 mm (implicit only). --quick runs a tiny film (dp = 2 cm, a few steps) on 1 and 2 threads instead, to
check that the benchmark works, not to measure. --multigrid-parts sets the implicit scheme's
implicit.multigrid_parts (the parts its multigrid hierarchies are cut into, V-cycled side by side), to N or, with
"threads", to each run's thread count (the results then differ between thread counts, within the solves'
tolerances).

Why a script around surge-bench and not an option of it: each thread count runs in a fresh process, so that the
OpenMP runtime reads OMP_WAIT_POLICY, GOMP_SPINCOUNT and OMP_PROC_BIND at its start (a running program cannot change
them for itself) and no run inherits another's thread pool, caches or heap; a run that fails costs its row, not the
table. The runs get OMP_WAIT_POLICY=PASSIVE, as `surge run` takes it, unless the caller set OMP_WAIT_POLICY or
GOMP_SPINCOUNT. The output names the machine, its cores and the three variables. Time it on an otherwise idle
machine.

Exit status: 0, 1 when a run failed (its row says how), 2 on bad input.
"""
import argparse
import os
import platform
import re
import subprocess
import sys

from surgepy import cli_checks

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROGRAM = "scaling"

DEBRIS = ["-s", "numerics.dp_m=0.04", "-s", "boulders.placement=graded", "-s", "boulders.count=60",
          "-s", "boulders.density_ratio=0.9", "-s", "boulders.seed=1"]
# name: (case file, C_h, wall layers (0: automatic), settings, {scheme: end time (s)}); the C_h and layers are the case
# file's own
SCENES = {
    "film": ("incline_film.ini", "1.0", "4", [], {"explicit": 0.05, "implicit": 0.1}),
    "film_fine": ("incline_film.ini", "1.0", "4", ["-s", "numerics.dp_m=0.0025"], {"explicit": 0.02, "implicit": 0.05}),
    "debris": ("debris_surge.ini", "1.8", "0", DEBRIS, {"explicit": 0.2, "implicit": 0.3}),
    "freydier": ("freydier_id1.ini", "1.8", "0", ["-s", "numerics.dp_m=0.0005"], {"implicit": 0.3}),
}
QUICK = {"tiny": ("incline_film.ini", "1.0", "4", ["-s", "numerics.dp_m=0.02"], {"explicit": 0.005, "implicit": 0.1})}
SERIAL_PHASES = ("contacts", "multigrid", "other")

RUN_LINE = re.compile(r"(\d+) fluid \+ (\d+) wall particles, (\d+) steps in [0-9.]+ s: ([0-9.]+) million "
                      r"particle-steps/s")
PHASES_LINE = re.compile(r"^\s+phases over (\d+) steps, ([0-9.]+) s:$")
PHASE_LINE = re.compile(r"^\s+(\w+)\s+([0-9.]+) s\s+([0-9.]+) %$")
COLUMNS = ("scene", "scheme", "fluid", "threads", "steps", "wall_s", "rate", "speed-up", "serial", "karp-flatt",
           "largest phase")
LEGEND = ("# fluid: fluid particles; wall_s: the steps' wall time (s); rate: million fluid particle-steps/s; speed-up: "
          "the rate over the 1-thread run's; serial: the share of wall_s in the phases on one thread (%s); "
          "karp-flatt: the serial fraction the speed-up implies; largest phase: its share of wall_s"
          % ", ".join(SERIAL_PHASES))


def cpu_description():
    """The CPU model, its physical cores (None where /proc/cpuinfo does not say), its logical CPUs and those this
    process may run on."""
    model, cores, package = platform.processor() or "unknown CPU", set(), None
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                key, _, value = line.partition(":")
                key, value = key.strip(), value.strip()
                if key == "model name":
                    model = value
                elif key == "physical id":
                    package = value
                elif key == "core id":
                    cores.add((package, value))
    except OSError:
        pass
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return model, len(cores) or None, os.cpu_count(), usable


def thread_counts(most):
    """1, 2, 4, ... up to most, and most itself."""
    counts, n = [], 1
    while n < most:
        counts.append(n)
        n *= 2
    return counts + [most]


def run_bench(bench, scene, scheme, threads, env, parts=None):
    """One surge-bench run: a dict of its figures and phases, or one with 'failed' saying why. parts: the implicit
    scheme's implicit.multigrid_parts, a number or 'threads' (None: the case's own)."""
    case, ch, layers, settings, end_times = scene
    cmd = [bench, os.path.join(ROOT, "cases", case), "--ch", ch, "--layers", layers, "--threads", str(threads),
           "--end-s", repr(end_times[scheme]), "-s", "numerics.scheme=" + scheme] + settings
    if parts is not None and scheme == "implicit":
        cmd += ["-s", "implicit.multigrid_parts=%d" % (threads if parts == "threads" else parts)]
    try:
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                              stdin=subprocess.DEVNULL)
    except OSError as e:
        return {"failed": "%s: %s" % (bench, e.strerror)}
    found = RUN_LINE.search(proc.stdout)
    result = {"output": proc.stdout, "phases": {}}
    for line in proc.stdout.splitlines():
        header = PHASES_LINE.match(line)
        phase = PHASE_LINE.match(line)
        if header:
            result["total_s"] = float(header.group(2))
        elif phase:
            result["phases"][phase.group(1)] = float(phase.group(2))
    if proc.returncode != 0 or not found or "total_s" not in result or "other" not in result["phases"]:
        last = proc.stdout.strip().splitlines()[-1:] or ["no output"]
        result["failed"] = "exit status %d: %s" % (proc.returncode, last[0][:160])
        return result
    result.update(fluid=int(found.group(1)), steps=int(found.group(3)), rate=float(found.group(4)))
    return result


def header_lines(bench, env, caller_policy, quick):
    model, cores, logical, usable = cpu_description()
    lines = ["# scaling: %s%s" % (bench, ", --quick (a check that it runs, not a measurement)" if quick else ""),
             "# machine: %s, %s physical cores, %d logical CPUs, %d usable by this process" %
             (model, cores if cores else "unknown", logical, usable),
             "# OpenMP: OMP_WAIT_POLICY=%s, GOMP_SPINCOUNT=%s (%s), OMP_PROC_BIND=%s" %
             (env.get("OMP_WAIT_POLICY", "unset"), env.get("GOMP_SPINCOUNT", "unset"),
              "set by the caller" if caller_policy else "set by scaling.py", env.get("OMP_PROC_BIND", "unset"))]
    return lines, (cores or logical, usable)


def table_row(name, scheme, threads, result, first):
    """The row's cells; first is the scene's 1-thread run."""
    if "failed" in result:
        return [name, scheme, "-", str(threads), "-", "-", "-", "-", "-", "-", "failed: " + result["failed"]]
    total = result["total_s"]
    serial = sum(result["phases"].get(p, 0.0) for p in SERIAL_PHASES) / total if total > 0 else 0.0
    largest = max(result["phases"], key=result["phases"].get)
    share = 100 * result["phases"][largest] / total if total > 0 else 0.0
    speedup, karp_flatt = "-", "-"
    if "failed" not in first and first["rate"] > 0:
        s = result["rate"] / first["rate"]
        speedup = "%.2f" % s
        if threads > 1 and s > 0:
            karp_flatt = "%.3f" % ((1 / s - 1 / threads) / (1 - 1 / threads))
    return [name, scheme, str(result["fluid"]), str(threads), str(result["steps"]), "%.3f" % total,
            "%.3f" % result["rate"], speedup, "%.3f" % serial, karp_flatt, "%s %.0f %%" % (largest, share)]


def print_cells(cells, widths):
    print("  ".join(c.ljust(w) for c, w in zip(cells, widths)).rstrip())
    sys.stdout.flush()


def phase_table(name, scheme, runs):
    """Each phase's seconds at every thread count that ran, and its speed-up from the first to the last of them."""
    ok = [(t, r) for t, r in runs if "failed" not in r]
    if not ok:
        return
    print()
    print("# %s %s, %d fluid particles: seconds per phase (speed-up from %d to %d threads)" %
          (name, scheme, ok[0][1]["fluid"], ok[0][0], ok[-1][0]))
    names = [p for p in ok[0][1]["phases"]]
    print("  ".join(["phase".ljust(15)] + ["%11s" % ("%d thr" % t) for t, _ in ok] + ["speed-up"]))
    for phase in names:
        seconds = [r["phases"].get(phase, 0.0) for _, r in ok]
        speedup = "%.2f" % (seconds[0] / seconds[-1]) if seconds[-1] > 0 else "-"
        print("  ".join([phase.ljust(15)] + ["%11.6f" % s for s in seconds] + ["%8s" % speedup]))
    print("  ".join(["total".ljust(15)] + ["%11.6f" % r["total_s"] for _, r in ok]))


def thread_list(text):
    """Comma-separated thread counts, rising, the first 1 (the speed-ups are against it)."""
    try:
        counts = [int(v) for v in text.split(",")]
    except ValueError:
        raise argparse.ArgumentTypeError("expected comma-separated whole numbers, got '%s'" % text)
    if counts[0] != 1 or any(b <= a for a, b in zip(counts, counts[1:])):
        raise argparse.ArgumentTypeError("expected rising thread counts starting at 1, got '%s'" % text)
    return counts


def multigrid_parts(text):
    """A positive number of parts, or 'threads'."""
    if text == "threads":
        return text
    try:
        return cli_checks.positive_int(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError("expected a whole number >= 1 or 'threads', got '%s'" % text)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bench", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge-bench"),
                        help="the surge-bench program (default build/surge-bench)")
    parser.add_argument("--max-threads", type=cli_checks.positive_int, metavar="N",
                        help="the most threads a run takes (default: the machine's physical cores, or the CPUs this "
                             "process may use where fewer)")
    parser.add_argument("--threads", type=thread_list, metavar="1,T2,...",
                        help="the thread counts to run, rising from 1 (instead of the powers of 2)")
    parser.add_argument("--scene", type=cli_checks.names(list(SCENES)),
                        help="comma-separated scenes among %s (default all)" % ", ".join(SCENES))
    parser.add_argument("--scheme", type=cli_checks.names(["explicit", "implicit"]),
                        help="comma-separated schemes among explicit, implicit (default both; the freydier scene "
                             "runs the implicit one only)")
    parser.add_argument("--quick", action="store_true",
                        help="a tiny scene on 1 and 2 threads, a few steps: that it runs, in seconds")
    parser.add_argument("--multigrid-parts", type=multigrid_parts, metavar="N|threads",
                        help="the implicit scheme's implicit.multigrid_parts: N, or each run's thread count "
                             "(default: the case's own, 1)")
    args = parser.parse_args()
    if args.quick and args.scene:
        parser.error("--quick runs its own tiny scene: leave out --scene")
    if args.threads and (args.max_threads or args.quick):
        parser.error("--threads lists the counts itself: leave out --max-threads and --quick")
    env = dict(os.environ)
    caller_policy = "OMP_WAIT_POLICY" in env or "GOMP_SPINCOUNT" in env
    if not caller_policy:
        env["OMP_WAIT_POLICY"] = "PASSIVE"
    lines, (cores, usable) = header_lines(args.bench, env, caller_policy, args.quick)
    if args.quick:
        scenes, counts = QUICK, [t for t in (1, 2) if t <= (args.max_threads or 2)]
    else:
        scenes = {name: SCENES[name] for name in args.scene or SCENES}
        counts = args.threads or thread_counts(args.max_threads or min(cores, usable))
    if args.multigrid_parts is not None:
        lines.append("# implicit.multigrid_parts = %s" % (
            "the run's thread count" if args.multigrid_parts == "threads" else args.multigrid_parts))
    for line in lines:
        print(line)
    widths = [10, 9, 7, 7, 6, 9, 9, 8, 6, 10, 0]
    print(LEGEND)
    print_cells(COLUMNS, widths)
    failures, tables, program_lines = 0, [], []
    for name, scene in scenes.items():
        for scheme in scene[4]:
            if args.scheme and scheme not in args.scheme:
                continue
            runs = []
            for threads in counts:
                result = run_bench(args.bench, scene, scheme, threads, env, args.multigrid_parts)
                if not program_lines:
                    program_lines = [line for line in result.get("output", "").splitlines()
                                     if line.startswith(("# program:", "# machine:"))]
                failures += "failed" in result
                runs.append((threads, result))
                print_cells(table_row(name, scheme, threads, result, runs[0][1]), widths)
            tables.append((name, scheme, runs))
    for name, scheme, runs in tables:
        phase_table(name, scheme, runs)
    if program_lines:
        print()
        print("# surge-bench's own lines: " + "; ".join(line.lstrip("# ") for line in program_lines))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
