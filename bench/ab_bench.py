#!/usr/bin/python3
"""ab_bench: the solver's throughput at an earlier commit (A) against the current build (B), interleaved.

  bench/ab_bench.py [--base f50cf94] [--pairs 3] [--ch 1.0,1.8] [--threads 1,2] [--end-s 0.1] [--new build]
                    [--set-b NAME=VALUE ...]

A is the commit --base, exported with `git archive` into build/ab/<commit>/ and built there in Release with the
current bench/bench.c (the public API it uses has not changed since f50cf94, but for the program and machine lines
it prints, left out for a base older than 87303e8, and the phase times, left out for a base without
surge_sim_phase_times), so that A and B run the same driver
on the same case file (this checkout's cases/incline_film.ini). For each configuration (C_h, threads) it runs
surge-bench A B A B ... --pairs times, one at a time, with OMP_WAIT_POLICY=PASSIVE, and prints each run's
particle-steps/s, the medians, each pair's ratio B/A, and the velocity error of both (which must agree). At
C_h 1.0 both run 4 wall layers, at other C_h the automatic number. --set-b passes parameters to B only (e.g. the
numerics of A's defaults, to time the same equations). Run it on an otherwise idle machine.
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys

from surgepy import cli_checks

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

LINE = re.compile(r"([0-9.]+) million particle-steps/s.*velocity error vs analytic start-up ([0-9.]+)")


def fail(message):
    cli_checks.fail("ab_bench", message)


def build_base(revision):
    """Exports and builds revision; returns the path of its surge-bench."""
    try:
        sha = subprocess.run(["git", "-C", ROOT, "rev-parse", "--verify", revision + "^{commit}"], check=True,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True).stdout.strip()
    except subprocess.CalledProcessError:
        fail("--base %s: not a commit of this repository" % revision)
    tree = os.path.join(ROOT, "build", "ab", sha[:12])
    bench = os.path.join(tree, "build", "surge-bench")
    if not os.path.isdir(os.path.join(tree, "sim")):
        shutil.rmtree(tree, ignore_errors=True)
        os.makedirs(tree)
        archive = subprocess.Popen(["git", "-C", ROOT, "archive", sha], stdout=subprocess.PIPE)
        subprocess.run(["tar", "-x", "-C", tree], stdin=archive.stdout, check=True)
        if archive.wait() != 0:
            fail("git archive %s failed" % sha)
    # the base's own place for bench.c: bench/, or tools/ in commits before the benchmarks had their folder
    bench_folder = "bench" if os.path.isfile(os.path.join(tree, "bench", "bench.c")) else "tools"
    shutil.copyfile(os.path.join(ROOT, "bench", "bench.c"), os.path.join(tree, bench_folder, "bench.c"))
    # a base older than 87303e8 has no surge_build_description(), one without the phase timers no
    # surge_sim_phase_times(): bench.c then leaves out its program/machine lines, its phase lines
    defines = []
    with open(os.path.join(tree, "sim", "include", "surge", "platform.h")) as f:
        if "surge_build_description" not in f.read():
            defines.append("-DSURGE_BENCH_WITHOUT_BUILD_INFO")
    with open(os.path.join(tree, "sim", "include", "surge", "sim.h")) as f:
        if "surge_sim_phase_times" not in f.read():
            defines.append("-DSURGE_BENCH_WITHOUT_PHASE_TIMES")
    flags = ["-DCMAKE_C_FLAGS=" + " ".join(defines)] if defines else []
    for cmd in (["cmake", "-S", tree, "-B", os.path.join(tree, "build"), "-DCMAKE_BUILD_TYPE=Release"] + flags,
                ["cmake", "--build", os.path.join(tree, "build"), "--target", "surge-bench", "-j%d" % os.cpu_count()]):
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if proc.returncode != 0:
            fail("building %s failed:\n%s" % (sha[:12], proc.stdout[-3000:]))
    return bench, sha[:12]


def run_bench(bench, case, ch, threads, end_s, settings=()):
    """particle-steps/s (millions) and velocity error of one run."""
    layers = "4" if float(ch) == 1.0 else "0"
    cmd = [bench, case, "--ch", ch, "--threads", str(threads), "--layers", layers, "--end-s", str(end_s)]
    for setting in settings:
        cmd += ["-s", setting]
    env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    match = LINE.search(proc.stdout)
    if proc.returncode != 0 or not match:
        fail("%s failed (exit status %d):\n%s" % (" ".join(cmd), proc.returncode, proc.stdout[-2000:]))
    return float(match.group(1)), float(match.group(2))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="f50cf94", help="commit A (default f50cf94)")
    parser.add_argument("--new", type=cli_checks.folder, default=os.path.join(ROOT, "build"),
                        help="build folder of B (default build/)")
    parser.add_argument("--pairs", type=cli_checks.positive_int, default=3)
    parser.add_argument("--ch", default="1.0,1.8", help="comma-separated C_h values")
    parser.add_argument("--threads", default="1,2", help="comma-separated thread counts")
    parser.add_argument("--end-s", type=cli_checks.positive, default=0.1)
    parser.add_argument("--set-b", action="append", default=[], metavar="NAME=VALUE",
                        help="a parameter for B's runs only (repeatable)")
    args = parser.parse_args()
    try:
        ch_values = args.ch.split(",")
        thread_values = [int(t) for t in args.threads.split(",")]
        if not all(float(c) > 0 for c in ch_values) or not all(t > 0 for t in thread_values):
            raise ValueError
    except ValueError:
        fail("--ch and --threads take comma-separated positive numbers (got --ch %s --threads %s)"
             % (args.ch, args.threads))
    for setting in args.set_b:
        if "=" not in setting:
            fail("--set-b %s: expected NAME=VALUE" % setting)
    new_bench = os.path.join(args.new, "surge-bench")
    if not os.access(new_bench, os.X_OK):
        fail("%s: no surge-bench there (build first)" % args.new)
    base_bench, sha = build_base(args.base)
    case = os.path.join(ROOT, "cases", "incline_film.ini")
    print("# ab_bench: A = %s, B = %s%s; %s, %g s of flow; %d pairs, A B A B ..." %
          (sha, args.new, "".join(" -s " + s for s in args.set_b), case, args.end_s, args.pairs))
    print("# C_h threads | A runs (million particle-steps/s) | B runs | median A | median B | ratios B/A | "
          "median ratio | velocity error A, B")
    for ch in ch_values:
        for threads in thread_values:
            a_runs, b_runs = [], []
            for _ in range(args.pairs):
                a_runs.append(run_bench(base_bench, case, ch, threads, args.end_s))
                b_runs.append(run_bench(new_bench, case, ch, threads, args.end_s, args.set_b))
            ratios = [b[0] / a[0] for a, b in zip(a_runs, b_runs)]
            print("%s %d | %s | %s | %.3f | %.3f | %s | %.2f | %.5f, %.5f" % (
                ch, threads, " ".join("%.3f" % r[0] for r in a_runs), " ".join("%.3f" % r[0] for r in b_runs),
                statistics.median(r[0] for r in a_runs), statistics.median(r[0] for r in b_runs),
                " ".join("%.2f" % r for r in ratios), statistics.median(ratios), a_runs[0][1], b_runs[0][1]))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
