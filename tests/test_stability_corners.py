#!/usr/bin/python3
"""Cheap corners of the stability map (tools/stability_map.py): configurations known to fail must be reported
as failed by the health monitor, with the check that failed, and the paper's default must stay healthy.

usage: test_stability_corners.py SURGE SOURCE_DIR WORK_DIR

All on cases/freydier_id1.ini at dp = 2 mm, 1.5 s of flow:
- paper default (C_h 1.8, Lind shifting, C_CFL 0.2, derived c0): healthy;
- no shifting: the belt drags fluid into the belt/upstream-wall corner ("particle crossed a wall");
- C_CFL = 2 (ten times the paper's): the explicit scheme blows up (caught as non-finite, density or wall check).
"""
import os
import subprocess
import sys

CASES = [
    ("paper_default", [], 0, None),
    ("no_shifting", ["-s", "shifting.form=none", "-s", "numerics.ch=1.3"], 1, ["particle crossed a wall"]),
    ("cfl_2", ["-s", "numerics.cfl=2"], 1, ["health check failed"]),
]


def main():
    surge, source, work = sys.argv[1:4]
    failed = 0
    for name, overrides, expected_rc, wanted in CASES:
        argv = [surge, "run", os.path.join(source, "cases", "freydier_id1.ini"), "-s", "numerics.dp_m=0.002",
                "-s", "walls.layers=0", "-s", "time.end_s=1.5", "-s", "output.progress_interval_s=0",
                "-s", "output.snapshot_interval_s=0.5"] + overrides + ["-o", os.path.join(work, name)]
        try:
            r = subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=900)
            rc, err = r.returncode, r.stderr
        except subprocess.TimeoutExpired:
            rc, err = None, "timed out"
        ok = rc == expected_rc and all(w in err for w in (wanted or []))
        if expected_rc == 1:
            ok = ok and all(w in err for w in ("particle", "step", "t =")) and \
                os.path.isfile(os.path.join(work, name, "last_good.vtp"))
        failed += not ok
        line = next((l for l in err.splitlines() if "health check failed" in l), "finished healthy" if rc == 0 else err)
        print("%-14s exit %s (expected %d): %s  %s" % (name, rc, expected_rc, line.strip(), "ok" if ok else "FAILED"))
        if not ok:
            print("  command: %s\n  stderr: %s" % (" ".join(argv), err))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
