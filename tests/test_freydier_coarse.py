#!/usr/bin/python3
"""A coarse Freydier ID1 run forms a front: uniform depth and toe speed within coarse bounds.

usage: test_freydier_coarse.py SURGE SOURCE_DIR WORK_DIR

dp = 2 mm (9 particles in h_n = 18.8 mm, half the paper's minimum of 15), C_h = 1.3, started from the lubrication
front and run for 8 s with the default (plain) continuity equation; metrics over the last 3 s
(tools/freydier_metrics.py). At this resolution the plain form lets the particles drift apart from their densities
(docs/validation/freydier.md), so the bounds are coarse: they catch a front that runs away or collapses (a broken
belt, wall, body force or viscosity), not the paper's targets. Measured 2026-11-22: zeta_h 0.174, zeta_f 0.123.
Before that date this test ran the renormalised divergence (numerics.continuity_correction) and held zeta_h to 5 %
(measured 0.8 %), but at dp = 2 mm that form slowly packs the bed layer near the front into the belt (the mean
height of the first layer falls from 0.50 to 0.31 dp by 8 s, tools/wall_contact.py) and the run crossed the belt at t = 7.74 s once the
belt-wall corner changed: it passed by a margin of time (docs/validation/stability.md).
"""
import os
import subprocess
import sys

from checks import load_module

freydier_metrics = load_module(os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "tools",
                                            "freydier_metrics.py"))

BOUNDS = {"zeta_h": 0.25, "zeta_f": 0.20}


def main():
    surge, source, work = sys.argv[1:4]
    run_dir = os.path.join(work, "id1_coarse")
    argv = [surge, "run", os.path.join(source, "cases", "freydier_id1.ini"), "-s", "numerics.dp_m=0.002",
            "-s", "numerics.ch=1.3", "-s", "walls.layers=0", "-s", "fluid.shape=lubrication", "-s", "time.end_s=8",
            "-s", "output.progress_interval_s=0", "-o", run_dir, "--overwrite"]
    r = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=1200)
    if r.returncode != 0:
        print("FAILED: %s exited %d\n%s" % (" ".join(argv), r.returncode, r.stderr))
        return 1
    m = freydier_metrics.compute(run_dir, window_s=3.0)
    stations = sorted(m["zeta_u"])
    failed = 0
    for key, bound in BOUNDS.items():
        ok = m[key] <= bound
        failed += not ok
        print("%-8s %.4f  (bound %g)  %s" % (key, m[key], bound, "ok" if ok else "FAILED"))
    print("zeta_fs  %.4f  (reported, not checked at this resolution)" % m["zeta_fs"])
    for station in stations:
        print("zeta_u at x* = %-4g %.4f  (reported, not checked at this resolution)" % (station, m["zeta_u"][station]))
    ok = abs(m["volume_end"] - 1) < 0.01
    failed += not ok
    print("fluid volume / initial %.5f  (bound 1 +- 0.01)  %s" % (m["volume_end"], "ok" if ok else "FAILED"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
