#!/usr/bin/python3
"""The implicit scheme with hypre's multigrid gives the same state whatever the thread count. With two threads the
viscous solve V-cycles its two velocity components at once, on two copies of its hierarchy (sim/src/scheme/implicit/amg.c); with one
thread one copy serves both in turn. The copies must be the same hierarchy, so the two runs must end in the same
state hash (the Freydier ID1 front at dp = 2 mm, C_h 1.8, 0.2 s, the multigrid forced for both solves).
Usage: test_implicit_threads.py SURGE ROOT OUTDIR"""
import csv
import os
import re
import subprocess
import sys

surge, root, out = sys.argv[1:4]
hashes = {}
failures = 0
for threads in (1, 2):
    folder = os.path.join(out, "threads_%d" % threads)
    cmd = [surge, "run", os.path.join(root, "cases", "freydier_id1.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.dp_m=0.002", "-s", "numerics.ch=1.8", "-s", "walls.layers=0", "-s", "fluid.shape=lubrication",
           "-s", "numerics.scheme=implicit", "-s", "implicit.preconditioner=amg", "-s", "time.end_s=0.2",
           "-s", "output.snapshot_interval_s=0", "-s", "output.progress_interval_s=0", "--threads", str(threads)]
    run = subprocess.run(cmd, capture_output=True, text=True)
    found = re.search(r"state hash ([0-9a-f]{16})", run.stderr)
    if run.returncode != 0 or not found:
        print("%d thread(s): the run failed\n%s\n%s" % (threads, " ".join(cmd), run.stderr[-1500:]))
        sys.exit(1)
    hashes[threads] = found.group(1)
    with open(os.path.join(folder, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    viscous = sum(int(r["viscous_iterations"]) for r in rows[1:])
    print("%d thread(s): state hash %s, %d steps, %d viscous iterations in the rows after the first"
          % (threads, hashes[threads], int(rows[-1]["step"]), viscous))
    if viscous <= 0:
        print("FAIL: no viscous iterations recorded, so the multigrid's viscous V-cycles were not exercised")
        failures += 1
if hashes[1] != hashes[2]:
    print("FAIL: the state hashes differ (1 thread %s, 2 threads %s)" % (hashes[1], hashes[2]))
    failures += 1
else:
    print("ok: 1 and 2 threads end in the same state hash")
sys.exit(1 if failures else 0)
