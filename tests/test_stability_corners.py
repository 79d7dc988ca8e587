#!/usr/bin/python3
"""Cheap corners of the stability map (studies/stability/stability_map.py): configurations known to fail must be
reported as failed by the health monitor, with the check that failed, and the paper's default must stay healthy.

usage: test_stability_corners.py SURGE SOURCE_DIR WORK_DIR

On cases/freydier_id1.ini:
- paper default (dp = 2 mm, 1.5 s; C_h 1.8, Lind shifting, C_CFL 0.2, derived c0): healthy;
- stiff belt corner, both continuity forms: a short domain (fluid 12-45 mm) at dp = 1 mm with c0 = 2.8 m/s, so
  that the corner's viscous pressure, nu u_b / (c0^2 dp) = 0.039, is twice that of the dp = 0.5 mm ID1 runs: it
  must stay healthy for 1 s (while the bed under the upstream wall mirrored its no-slip velocity about the belt's,
  it dragged a particle under the wall at t = 0.39 s: "particle crossed a wall");
- no shifting, C_h 1.3, c0 = 5 x the expected speed (2.84 m/s), without the walls' no-penetration term and
  face repulsion, with the plain continuity form and no density relaxation (the defaults before 2026-11-24, but
  for the initial rows' spacing; with the renormalised form it blows up instead, non-finite at t = 0.42 s): the
  particles layer along the belt and one is carried under the upstream wall (t = 1.62 s, 2026-11-24; 1.89 s on
  the square initial lattice; docs/validation/stability.md); the wall check stops it (the run is 3 s long so that
  a failure that comes somewhat later, e.g. with another compiler's rounding, still counts);
- the same with the defaults (no-penetration, face repulsion, renormalised continuity, density relaxation):
  healthy for the 3 s;
- c0 = 2 x the expected speed (1.13 m/s): too soft to carry its own weight; the density check stops it;
- C_CFL = 2 (ten times the paper's): the explicit scheme blows up (caught as non-finite, density or wall check).
"""
import os
import subprocess
import sys

COARSE = ["-s", "numerics.dp_m=0.002", "-s", "time.end_s=1.5"]
STIFF_CORNER = ["-s", "domain.length_m=0.07", "-s", "domain.height_m=0.04", "-s", "fluid.x1_m=0.045",
                "-s", "walls.upstream_height_m=0.03", "-s", "numerics.c0_mps=2.8", "-s", "time.end_s=1"]
NO_SHIFTING_SOFT_CORNER = ["-s", "numerics.dp_m=0.002", "-s", "time.end_s=3", "-s", "shifting.form=none",
                           "-s", "numerics.ch=1.3", "-s", "numerics.c0_factor=5"]
CASES = [
    ("paper_default", COARSE, 0, None),
    ("stiff_corner_renormalised", STIFF_CORNER + ["-s", "numerics.continuity_correction=true"], 0, None),
    ("stiff_corner_plain", STIFF_CORNER + ["-s", "numerics.continuity_correction=false"], 0, None),
    ("no_shifting_soft_corner", NO_SHIFTING_SOFT_CORNER + ["-s", "walls.no_penetration=false",
                                                    "-s", "walls.face_repulsion_reach_dp=0",
                                                    "-s", "numerics.continuity_correction=false",
                                                    "-s", "numerics.density_relaxation=0"], 1,
     ["particle crossed a wall"]),
    ("no_shifting_soft_corner_no_penetration", NO_SHIFTING_SOFT_CORNER, 0, None),
    ("c0_factor_2", COARSE + ["-s", "numerics.c0_factor=2"], 1, ["density far from rho0"]),
    ("cfl_2", COARSE + ["-s", "numerics.cfl=2"], 1, ["health check failed"]),
]


def main():
    surge, source, work = sys.argv[1:4]
    failed = 0
    for name, overrides, expected_rc, wanted in CASES:
        argv = [surge, "run", os.path.join(source, "cases", "freydier_id1.ini"), "-s", "walls.layers=0",
                "-s", "output.progress_interval_s=0", "-s", "output.snapshot_interval_s=0.5"] + overrides + \
               ["-o", os.path.join(work, name), "--overwrite"]
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
        print("%-26s exit %s (expected %d): %s  %s" % (name, rc, expected_rc, line.strip(), "ok" if ok else "FAILED"))
        if not ok:
            print("  command: %s\n  stderr: %s" % (" ".join(argv), err))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
