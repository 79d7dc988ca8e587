#!/usr/bin/python3
"""The implicit scheme's contact distance (implicit.contact_reach_dp): on the Freydier front (dp 2 mm, C_h 1.3, 1 s)
no fluid particle ends closer to the upstream wall's face or to the belt than the distance, and the front presses
particles onto it, so the closest sit at it. Run at two distances: a scheme that ignored the parameter (the explicit
scheme's 0.25 dp, say) would put particles nearer at 0.45 dp or none at 0.3 dp.
Usage: test_implicit_contact.py SURGE ROOT OUTDIR"""
import os
import subprocess
import sys

surge, root, out = sys.argv[1:4]
from surgepy.vtp import read_vtp  # noqa: E402

DP_M, FACE_X_M = 0.002, 0.012  # cases/freydier_id1.ini: the upstream wall's face; the belt's face is y = 0
failures = 0
for reach in (0.3, 0.45):
    folder = os.path.join(out, "reach_%g" % reach)
    cmd = [surge, "run", os.path.join(root, "cases", "freydier_id1.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.scheme=implicit", "-s", "numerics.ch=1.3", "-s", "numerics.dp_m=%g" % DP_M,
           "-s", "fluid.shape=lubrication", "-s", "time.end_s=1", "-s", "output.snapshot_interval_s=1",
           "-s", "output.progress_interval_s=0", "-s", "implicit.contact_reach_dp=%g" % reach, "--threads", "1"]
    if subprocess.run(cmd, capture_output=True, text=True).returncode != 0:
        print("contact %g dp: the run failed" % reach)
        failures += 1
        continue
    last = sorted(f for f in os.listdir(folder) if f.startswith("snap_") and f.endswith(".vtp"))[-1]
    snap = read_vtp(os.path.join(folder, last))
    fluid = snap["kind"] == 0
    points = snap["points"][fluid]
    closest = min(((points[:, 0] - FACE_X_M) / DP_M).min(), (points[:, 1] / DP_M).min())
    ok = abs(closest - reach) < 1e-3
    print("contact %g dp: closest fluid particle to the upstream wall or the belt %.6f dp (within 1e-3 of %g) %s"
          % (reach, closest, reach, "ok" if ok else "FAILED"))
    failures += not ok
sys.exit(1 if failures else 0)
