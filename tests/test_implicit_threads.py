#!/usr/bin/python3
"""The implicit scheme with hypre's multigrid gives the same state whatever the thread count. With two threads the
viscous solve V-cycles its two velocity components at once, on two copies of its hierarchy (sim/src/scheme/implicit/amg.c); with one
thread one copy serves both in turn. The copies must be the same hierarchy, so the two runs must end in the same
state hash (the Freydier ID1 front at dp = 2 mm, C_h 1.8, 0.2 s, the multigrid forced for both solves).

With PARTS > 1 each hierarchy is cut into that many parts (implicit.multigrid_parts), built and V-cycled side by side
on the threads: the result depends on the parts, not on the threads, so 1, 2 and 4 threads (more threads than parts'
copies, the builds handed out in whatever order the threads come) must again end in the same state, and that state
must differ from the one of a single hierarchy (else the parts were not used).
Usage: test_implicit_threads.py SURGE ROOT OUTDIR [PARTS]"""
import csv
import os
import re
import subprocess
import sys

surge, root, out = sys.argv[1:4]
parts = int(sys.argv[4]) if len(sys.argv) > 4 else 1
hashes = {}
failures = 0
for threads, run_parts in ((1, parts), (2, parts)) + (((4, parts), (0, 1)) if parts > 1 else ()):
    folder = os.path.join(out, "threads_%d_parts_%d" % (threads, run_parts))
    cmd = [surge, "run", os.path.join(root, "cases", "freydier_id1.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.dp_m=0.002", "-s", "numerics.ch=1.8", "-s", "walls.layers=0", "-s", "fluid.shape=lubrication",
           "-s", "numerics.scheme=implicit", "-s", "implicit.preconditioner=amg", "-s", "time.end_s=0.2",
           "-s", "output.snapshot_interval_s=0", "-s", "output.progress_interval_s=0",
           "-s", "implicit.multigrid_parts=%d" % run_parts, "--threads", str(max(threads, 1))]
    run = subprocess.run(cmd, capture_output=True, text=True)
    found = re.search(r"state hash ([0-9a-f]{16})", run.stderr)
    if run.returncode != 0 or not found:
        print("%d thread(s): the run failed\n%s\n%s" % (threads, " ".join(cmd), run.stderr[-1500:]))
        sys.exit(1)
    hashes[threads] = found.group(1)
    with open(os.path.join(folder, "diagnostics.csv")) as f:
        rows = list(csv.DictReader(f))
    viscous = sum(int(r["viscous_iterations"]) for r in rows[1:])
    print("%d thread(s), %d part(s): state hash %s, %d steps, %d viscous iterations in the rows after the first"
          % (max(threads, 1), run_parts, hashes[threads], int(rows[-1]["step"]), viscous))
    if viscous <= 0:
        print("FAIL: no viscous iterations recorded, so the multigrid's viscous V-cycles were not exercised")
        failures += 1
counts = [t for t in (1, 2, 4) if t in hashes]
if len({hashes[t] for t in counts}) != 1:
    print("FAIL: the state hashes differ (%s)" % ", ".join("%d threads %s" % (t, hashes[t]) for t in counts))
    failures += 1
else:
    print("ok: %s threads end in the same state hash" % " and ".join(map(str, counts)))
if parts > 1 and hashes[0] == hashes[1]:
    print("FAIL: %d parts end in the state of one hierarchy (%s): the parts were not used" % (parts, hashes[0]))
    failures += 1
sys.exit(1 if failures else 0)
