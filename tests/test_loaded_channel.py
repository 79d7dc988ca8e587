#!/usr/bin/python3
"""The loaded channel with the implicit scheme (docs/validation/poiseuille_loaded.md).

dilute: at the dilute end, coarse against converged ("Convergence with the implicit scheme"):
cases/poiseuille_loaded.ini at phi 0.1 (seed 1, 48 discs), r/dp 3, the implicit scheme at its own step with the
shipped settings (the lubrication model on), 1 s.

At phi 0.1 the implicit sweep converges (mu_eq/mu0 1.1131, 1.1378, 1.1496 and 1.1610 at r/dp 4, 6, 8 and 12,
changes of 2.2, 1.0 and 1.0 %); the coarse run reads 1.0941, 5.8 % below the r/dp 12 value. With the rest-density
correction reading the spacing against the lattice's kernel sum in this closed channel it read 1.0541, 9.2 % below
(docs/method.md, "Closed domains").

Checks: the run ends healthy; mu_eq/mu0 (eq. 19, the study's measure over 0.8-1 s) within 7 % of the r/dp 12 value;
the largest density deviation over 0.5-1 s below 0.05.

kicks: the dense end, phi 0.5 (seed 1, 239 discs), r/dp 3, the lubrication model off, 0.4 s at the scheme's own step
(0.05 s) and 0.25 s at a fixed 0.01 s, a snapshot of the discs every 0.01 s ("Discs kicked apart in one step"). A
fluid particle kept off two faces nearly back to back gave each disc its own push whole: two discs whose gap crossed
0.9 dp were kicked apart by 0.07-0.09 m/s (own step) and 0.19 m/s (0.01 s) in one step and back in the next, where
neighbouring discs differ by about 0.01 m/s. Checks: both runs end healthy; after the first step (the discs start
from rest) no disc's velocity changes by more than 0.02 m/s from one snapshot to the next (measured 0.0074 and
0.0062 m/s; 0.0868 and 0.1870 before the reactions were shared).

Usage: test_loaded_channel.py SURGE ROOT OUTDIR dilute|kicks"""
import csv
import os
import subprocess
import sys

surge, root, out, group = sys.argv[1:5]
sys.path.insert(0, os.path.join(root, "studies", "poiseuille_loaded"))
sys.path.insert(0, os.path.join(root, "python"))
import poiseuille_loaded  # noqa: E402
from surgepy import vtp  # noqa: E402

CONVERGED = 1.1610  # seed 1, r/dp 12, the study's CSV
failures = 0


def report(text, ok, detail=""):
    global failures
    print("%s: %s%s" % (text, "ok" if ok else "FAILED", "" if ok or not detail else " (%s)" % detail))
    failures += not ok


def group_dilute():
    folder = os.path.join(out, "phi0.1_r3")
    cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.dp_m=0.006666666666666667", "-s", "boulders.solid_fraction=0.1", "-s", "boulders.seed=1",
           "-s", "numerics.scheme=implicit", "-s", "output.progress_interval_s=0", "--threads", "1"]
    run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    report("the loaded channel at phi 0.1, r/dp 3, runs 1 s healthy", run.returncode == 0, run.stderr[-1500:])
    if run.returncode == 0:
        u_max, mu_ratio, phi, discs = poiseuille_loaded.measure(folder)
        change = mu_ratio / CONVERGED - 1
        print("mu_eq/mu0 = %.4f (phi %.4f, %d discs), %+.1f %% from the r/dp 12 value %.4f"
              % (mu_ratio, phi, discs, 100 * change, CONVERGED))
        report("mu_eq/mu0 within 7 % of the converged value", abs(change) < 0.07, "%+.1f %%" % (100 * change))
        with open(os.path.join(folder, "diagnostics.csv")) as f:
            late = [float(r["max_density_deviation"]) for r in csv.DictReader(f) if float(r["time_s"]) >= 0.5]
        print("largest density deviation over 0.5-1 s: %.4f" % max(late))
        report("largest density deviation below 0.05 over 0.5-1 s", max(late) < 0.05, "%.4f" % max(late))


def group_kicks():
    for name, folder_name, extra, first_kept_s in (
            ("own step", "kicks_own_step", ["-s", "time.end_s=0.4"], 0.06),
            ("step 0.01 s", "kicks_fixed_step", ["-s", "time.end_s=0.25", "-s", "numerics.dt_fixed_s=0.01"], 0.015)):
        folder = os.path.join(out, folder_name)
        cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
               "-s", "numerics.dp_m=0.006666666666666667", "-s", "boulders.solid_fraction=0.5",
               "-s", "boulders.seed=1", "-s", "numerics.scheme=implicit", "-s", "contacts.lubrication=false",
               "-s", "output.snapshot_interval_s=0.01", "-s", "output.progress_interval_s=0", "--threads", "1"] + extra
        run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        report("phi 0.5, r/dp 3, %s: the run ends healthy" % name, run.returncode == 0, run.stderr[-1500:])
        if run.returncode != 0:
            continue
        series = [vtp.read_vtp(os.path.join(folder, f)) for _, f in vtp.read_pvd(os.path.join(folder, "boulders.pvd"))]
        largest, when = 0.0, 0.0
        for before, after in zip(series, series[1:]):
            if float(before["time_s"]) < first_kept_s:
                continue
            change = ((after["velocity_mps"][:, :2] - before["velocity_mps"][:, :2]) ** 2).sum(axis=1).max() ** 0.5
            if change > largest:
                largest, when = change, float(after["time_s"])
        print("%s: largest change of a disc's velocity between snapshots after the first step %.4f m/s (t = %.3f s)"
              % (name, largest, when))
        report("%s: no disc's velocity changes by more than 0.02 m/s between snapshots" % name, largest < 0.02,
               "%.4f m/s at t = %.3f s" % (largest, when))


{"dilute": group_dilute, "kicks": group_kicks}[group]()
print("%d check(s) failed" % failures if failures else "all checks passed")
sys.exit(1 if failures else 0)
