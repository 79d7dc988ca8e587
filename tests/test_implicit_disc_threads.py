#!/usr/bin/python3
"""The implicit scheme with discs gives the same state whatever the thread count: runs on 1 and 2 threads end in the
same state hash. Two scenes from cases/boulder_settling.ini:
- the case itself (one disc, 4,000 fluid particles), 0.1 s: below the implicit scheme's 10,000 fluid particles its
  solves' loops stay on one thread, and the neighbour lists, the walls' mDBC states, the disc particles' placement
  and the health check are shared;
- three discs at dp = 1 mm (23,428 fluid particles), 0.05 s: the solves' loops, the disc coupling's and the
  multigrid's V-cycles (two copies of the viscous hierarchy) are shared too.
Usage: test_implicit_disc_threads.py SURGE ROOT OUTDIR"""
import os
import re
import subprocess
import sys

surge, root, out = sys.argv[1:4]
SCENES = {
    "one_disc": ["-s", "time.end_s=0.1"],
    "three_discs": ["-s", "time.end_s=0.05", "-s", "numerics.dp_m=0.001",
                    "-s", "boulders.list_m=0.025 0.17 0.0125, 0.075 0.17 0.0125, 0.05 0.1 0.0125"],
}
# the fluid particles each scene must have: below and above the implicit scheme's threshold for shared loops
# (WIDE_FLUID_PARTICLES, sim/src/scheme/implicit/implicit.h)
WIDE = 10000

failures = 0
for name, settings in SCENES.items():
    hashes = {}
    for threads in (1, 2):
        folder = os.path.join(out, "%s_threads_%d" % (name, threads))
        cmd = [surge, "run", os.path.join(root, "cases", "boulder_settling.ini"), "-o", folder, "--overwrite",
               "-s", "numerics.scheme=implicit", "-s", "output.snapshot_interval_s=0",
               "-s", "output.progress_interval_s=0", "--threads", str(threads)] + settings
        run = subprocess.run(cmd, capture_output=True, text=True)
        found = re.search(r"state hash ([0-9a-f]{16})", run.stderr)
        particles = re.search(r"(\d+) fluid \+ (\d+) wall particles", run.stderr)
        if run.returncode != 0 or not found or not particles:
            print("FAIL: %s, %d thread(s): the run failed\n%s\n%s" % (name, threads, " ".join(cmd), run.stderr[-1500:]))
            sys.exit(1)
        hashes[threads] = found.group(1)
        fluid = int(particles.group(1))
        print("%s, %d thread(s): %d fluid particles, state hash %s" % (name, threads, fluid, hashes[threads]))
    wide = fluid >= WIDE
    if wide != (name == "three_discs"):
        print("FAIL: %s has %d fluid particles, expected %s %d" % (name, fluid,
                                                                    "at least" if name == "three_discs" else "below",
                                                                    WIDE))
        failures += 1
    if hashes[1] != hashes[2]:
        print("FAIL: %s: the state hashes differ (1 thread %s, 2 threads %s)" % (name, hashes[1], hashes[2]))
        failures += 1
    else:
        print("ok: %s: 1 and 2 threads end in the same state hash" % name)
sys.exit(1 if failures else 0)
