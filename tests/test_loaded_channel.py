#!/usr/bin/python3
"""The loaded channel with the implicit scheme (docs/validation/poiseuille_loaded.md).

dilute: at the dilute end, coarse against converged ("Convergence with the implicit scheme"):
cases/poiseuille_loaded.ini at phi 0.1 (seed 1, 48 discs), r/dp 3, the implicit scheme at its own step with the
shipped settings but the cut-off lubrication model (contacts.lubrication_resolved = cutoff with the
sliding film), 1 s.

At phi 0.1 the implicit sweep converges (mu_eq/mu0 1.1131, 1.1378, 1.1496 and 1.1610 at r/dp 4, 6, 8 and 12,
changes of 2.2, 1.0 and 1.0 %; without the lubrication model); the coarse run reads 1.1097, 4.4 % below the r/dp 12
value (1.0941, 5.8 % below, with the lubrication films in the contact solver after the solve). With the rest-density
correction reading the spacing against the lattice's kernel sum in this closed channel it read 1.0541, 9.2 % below
(docs/method.md, "Closed domains").

Checks: the run ends healthy; mu_eq/mu0 (eq. 19, the study's measure over 0.8-1 s) within 7 % of the r/dp 12 value;
the largest density deviation over 0.5-1 s below 0.05.

kicks: the dense end, phi 0.5 (seed 1, 239 discs), r/dp 3, the lubrication model off, 0.4 s at the scheme's own step
(0.05 s) and 0.25 s at a fixed 0.01 s, a snapshot of the discs every 0.01 s (docs/method.md, "The implicit scheme",
"Between two solids"). A fluid particle kept off two faces nearly back to back gave each disc its own push whole: two
discs whose gap crossed 0.9 dp were kicked apart by 0.07-0.09 m/s (own step) and 0.19 m/s (0.01 s) in one step and
back in the next, where neighbouring discs differ by about 0.01 m/s. Checks: both runs end healthy; after the first
step (the discs start from rest) no disc's velocity changes by more than 0.02 m/s from one snapshot to the next
(measured 0.0074 and 0.0062 m/s; 0.0868 and 0.1870 before the reactions were shared).

packing: boulders.pack_fluid on a 0.3 m cut of the channel at phi 0.5, r/dp 4 (docs/boulders.md, "Placement"), at
the start. Without it the lattice leaves out the sites within a quarter spacing of a disc, and the fluid is short of
its room by 0.5 phi / ((r/dp)(1 - phi)), 1/8 here, and by the sites of narrow gaps. Checks: the fluid fills at least
0.97 of its room packed (measured 0.9780; 0.8721 without); within 2 dp of a disc the kernel sums over the lattice's
have a mean within 2 % of 1 and a spread below 0.015 (measured 0.9866 and 0.0090; without 0.9267 and 0.0403); no
particle lies closer to a disc's surface than the contact distance, 0.45 dp (without: 0.250 dp); 1 and 2 threads
pack alike (state hash); a run stopped half way and restarted from its checkpoint ends in the uninterrupted run's
state hash; the whole channel packed at phi 0.3, r/dp 4 runs 0.3 s (with the rest-density correction counting only an
excess next to a disc it stopped at 0.20 s, a particle in the wedge under a disc 0.2 dp above the plate at 1.137 rho0).

schemes: the dense end with both schemes (docs/validation/poiseuille_loaded.md, "Narrow gaps"): the shipped channel
at phi 0.5 (seed 1, 239 discs), r/dp 3, the cut-off lubrication model, 1 s, explicit and implicit. The explicit scheme
takes the films in the contact solver's sub-steps, whose disc velocities its fluid sees at the next step; the
implicit scheme inside its solves. Checks: both runs end healthy; their mu_eq/mu0 (0.8-1 s) within 8 % of each other
(measured: implicit 1.9959, explicit 2.0540, -2.8 %; without the model -24.4 %, and with the films after the implicit
solve, in the contact solver, the implicit run stopped at 0.76 s).

measured: the dense end with the measured squeeze film (contacts.lubrication_resolved = measured, docs/boulders.md):
the shipped channel at phi 0.5 (seed 1, 239 discs), r/dp 3, packed, implicit, the sliding film, 1 s. With the cut-off model the
coarse run reads 49 % below the r/dp 8 run of the same model's sweep; with the measured film the whole sweep reads
3.6357, 3.7979, 4.0037 and 4.1917 at r/dp 3, 4, 6 and 8 (docs/validation/poiseuille_loaded.md). Checks: the run ends
healthy; mu_eq/mu0 within 15 % of the measured film's r/dp 8 value (measured -13.3 %; the cut-off model at r/dp 3
reads 2.1404, -48.9 %).

tangential: the dense end with the tangential film (contacts.lubrication_tangential = reynolds, docs/boulders.md): the
shipped channel at phi 0.5 (seed 1, 239 discs), r/dp 4, packed, implicit, the measured squeeze film, 1 s. Its sweep
reads 6.2933, 5.7809, 5.3977, 5.2962 and 5.2773 at r/dp 3, 4, 6, 8 and 12, converging from above (-0.4 % from r/dp 8
to 12; docs/validation/poiseuille_loaded.md, "The wall layer and the tangential film"). Checks: the run ends
healthy; mu_eq/mu0 within 12 % of the r/dp 12 value (measured +9.5 %; with the sliding film, r/dp 4
reads 3.7979, -28 %); at r/dp 3 for 0.3 s the same state hash on 1 and 2 threads.

share: the two schemes with one share (contacts.lubrication_share, docs/validation/poiseuille_loaded.md, "Both
schemes with the measured films"): the shipped channel at phi 0.5 (seed 1, 239 discs), r/dp 3, both films (measured
squeeze film, tangential film), 0.3 s; the explicit scheme with its own share, the implicit one with its own and with
the explicit scheme's. Each scheme's share is measured on a lone disc, where the explicit SPH resolves more of a film
than the implicit one; in the channel the two resolve alike, so the share taken decides the dense end. Checks: the
three runs end healthy; mu_eq/mu0 (0.2-0.3 s) of the implicit scheme with the explicit share within 8 % of the
explicit scheme's (measured 4.7979 against 4.4776, +7.2 %); with its own share at least 20 % above it (measured 6.4874,
+44.9 %).

Usage: test_loaded_channel.py SURGE ROOT OUTDIR dilute|kicks|packing|schemes|measured|tangential|share"""
import csv
import math
import os
import re
import subprocess
import sys

import numpy as np

surge, root, out, group = sys.argv[1:5]
sys.path.insert(0, os.path.join(root, "studies", "poiseuille_loaded"))
sys.path.insert(0, os.path.join(root, "python"))
import poiseuille_loaded  # noqa: E402
from surgepy import vtp  # noqa: E402

CONVERGED = 1.1610  # seed 1, r/dp 12, the study's CSV
MEASURED_FINEST, MEASURED_BOUND = 4.1917, 0.15  # phi 0.5, packed, measured film: r/dp 8, the study's CSV
CUTOFF_R3 = 2.1404  # phi 0.5, packed, the cut-off model (h_c 1 dp) at r/dp 3, the study's CSV
TANGENTIAL_FINEST, TANGENTIAL_BOUND = 5.2773, 0.12  # phi 0.5, packed, the tangential film: r/dp 12 (the page's table)
failures = 0


def report(text, ok, detail=""):
    global failures
    print("%s: %s%s" % (text, "ok" if ok else "FAILED", "" if ok or not detail else " (%s)" % detail))
    failures += not ok


def group_dilute():
    folder = os.path.join(out, "phi0.1_r3")
    cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.dp_m=0.006666666666666667", "-s", "boulders.solid_fraction=0.1", "-s", "boulders.seed=1",
           "-s", "numerics.scheme=implicit", "-s", "contacts.lubrication_resolved=cutoff",
           "-s", "contacts.lubrication_tangential=sliding", "-s", "output.progress_interval_s=0", "--threads", "1"]
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


def kernel_ratios(points, kinds, period_m, dp, h, near):
    """Each fluid particle's kernel sum (fluid, walls and discs, periodic in x) over the square lattice's, for the
    fluid particles `near` selects"""
    alpha = 7 / (4 * math.pi * h * h)

    def kernel(r):
        q = np.minimum(r / h, 2.0)
        return alpha * (1 - q / 2) ** 4 * (2 * q + 1)
    offsets = np.arange(-8, 9) * dp
    lattice = kernel(np.hypot(*np.meshgrid(offsets, offsets))).sum()
    sums = []
    for a in np.nonzero((kinds == 0) & near)[0]:
        dx = points[:, 0] - points[a, 0]
        dx -= period_m * np.round(dx / period_m)
        sums.append(kernel(np.hypot(dx, points[:, 1] - points[a, 1])).sum() / lattice)
    return np.array(sums)


def group_packing():
    dp, length, height = 0.005, 0.3, 0.6
    base = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "--overwrite",
            "-s", "numerics.dp_m=%r" % dp, "-s", "domain.length_m=%r" % length, "-s", "fluid.x1_m=%r" % length,
            "-s", "boulders.solid_fraction=0.5", "-s", "numerics.scheme=implicit", "-s", "output.progress_interval_s=0"]
    hashes, runs = {}, {}
    for name, extra in (("packed", ["-s", "boulders.pack_fluid=true"]), ("cut", [])):
        for threads, end_s in (("1", "0.1"), ("2", "0.1"), ("1", "0.05")):
            if name == "cut" and (threads, end_s) != ("1", "0.1"):
                continue
            folder = os.path.join(out, "%s_%s_%s" % (name, threads, end_s))
            run = subprocess.run(base + ["-o", folder, "--threads", threads, "-s", "time.end_s=" + end_s] + extra,
                                 capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
            report("%s, %s thread(s), to %s s: the run ends healthy" % (name, threads, end_s), run.returncode == 0,
                   run.stderr[-1500:])
            found = re.search(r"state hash ([0-9a-f]{16})", run.stderr)
            hashes[name, threads, end_s] = found.group(1) if found else None
            runs[name, threads, end_s] = folder
    for name in ("packed", "cut"):
        folder = runs[name, "1", "0.1"]
        snap = vtp.read_vtp(os.path.join(folder, "snap_000000000.vtp"))
        discs = vtp.read_vtp(os.path.join(folder, "boulders_000000000.vtp"))
        points, kinds = snap["points"][:, :2].astype(float), snap["kind"]
        room = length * height - math.pi * (discs["radius_m"].astype(float) ** 2).sum()
        share = (kinds == 0).sum() * dp * dp / room
        centres = discs["points"][:, :2].astype(float)
        gap = np.full(len(points), np.inf)
        for (cx, cy), r in zip(centres, discs["radius_m"].astype(float)):
            dx = points[:, 0] - cx
            dx -= length * np.round(dx / length)
            gap = np.minimum(gap, np.hypot(dx, points[:, 1] - cy) - r)
        near = gap < 2 * dp
        sums = kernel_ratios(points, kinds, length, dp, 1.8 * math.sqrt(2) * dp, near)
        closest = gap[kinds == 0].min() / dp
        print("%s: %d fluid particles, %.4f of the room; within 2 dp of a disc the kernel sums %.4f +- %.4f (%d "
              "particles); closest to a disc's surface %.3f dp" % (name, (kinds == 0).sum(), share, sums.mean(),
                                                                    sums.std(), len(sums), closest))
        if name == "packed":
            report("packed: the fluid fills at least 0.97 of its room", share >= 0.97, "%.4f" % share)
            report("packed: within 2 dp of a disc the kernel sums' mean within 2 % of 1 and spread below 0.015",
                   abs(sums.mean() - 1) < 0.02 and sums.std() < 0.015, "%.4f +- %.4f" % (sums.mean(), sums.std()))
            report("packed: no fluid particle closer to a disc than the contact distance (0.45 dp)",
                   closest > 0.45 - 1e-6, "%.3f dp" % closest)
    report("packed: 1 and 2 threads end in the same state hash",
           hashes["packed", "1", "0.1"] is not None and hashes["packed", "1", "0.1"] == hashes["packed", "2", "0.1"],
           str(hashes))
    half = runs["packed", "1", "0.05"]
    again = subprocess.run([surge, "run", "--restart", os.path.join(half, "checkpoint.bin"), "-o", half,
                            "--threads", "1", "-s", "time.end_s=0.1"], capture_output=True, text=True,
                           env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    found = re.search(r"state hash ([0-9a-f]{16})", again.stderr)
    report("packed: restarted half way, the run ends in the uninterrupted run's state hash",
           again.returncode == 0 and found is not None and found.group(1) == hashes["packed", "1", "0.1"],
           again.stderr[-1500:])
    whole = subprocess.run([surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "--overwrite",
                            "-o", os.path.join(out, "packed_phi0.3"), "-s", "numerics.dp_m=0.005",
                            "-s", "boulders.solid_fraction=0.3", "-s", "numerics.scheme=implicit",
                            "-s", "contacts.lubrication=false", "-s", "boulders.pack_fluid=true",
                            "-s", "time.end_s=0.3", "-s", "output.progress_interval_s=0", "--threads", "1"],
                           capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    report("packed: the whole channel at phi 0.3, r/dp 4 runs 0.3 s healthy", whole.returncode == 0,
           whole.stderr[-1500:])


def group_schemes():
    values = {}
    for scheme in ("explicit", "implicit"):
        folder = os.path.join(out, "phi0.5_r3_" + scheme)
        cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
               "-s", "numerics.dp_m=0.006666666666666667", "-s", "boulders.solid_fraction=0.5", "-s", "boulders.seed=1",
               "-s", "numerics.scheme=" + scheme, "-s", "contacts.lubrication_resolved=cutoff",
               "-s", "contacts.lubrication_tangential=sliding", "-s", "output.progress_interval_s=0", "--threads", "1"]
        run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        report("%s: the loaded channel at phi 0.5, r/dp 3, runs 1 s healthy" % scheme, run.returncode == 0,
               run.stderr[-1500:])
        if run.returncode == 0:
            values[scheme] = poiseuille_loaded.measure(folder)[1]
            print("%s: mu_eq/mu0 = %.4f" % (scheme, values[scheme]))
    if len(values) == 2:
        change = values["implicit"] / values["explicit"] - 1
        print("implicit against explicit: %+.1f %%" % (100 * change))
        report("the schemes' mu_eq/mu0 within 8 % of each other", abs(change) < 0.08, "%+.1f %%" % (100 * change))


def dense_run(name, what, dp, extra, finest, bound, note=""):
    """phi 0.5 (seed 1), packed, implicit, the measured squeeze film and extra, 1 s at dp: the run ends healthy and
    mu_eq/mu0 lies within bound of the finest run's value"""
    folder = os.path.join(out, name)
    cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
           "-s", "numerics.dp_m=%r" % dp, "-s", "boulders.solid_fraction=0.5", "-s", "boulders.seed=1",
           "-s", "numerics.scheme=implicit", "-s", "boulders.pack_fluid=true",
           "-s", "contacts.lubrication_resolved=measured", "-s", "output.progress_interval_s=0", "--threads", "1"] + extra
    run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    report("%s: the loaded channel at phi 0.5, r/dp %g, packed, runs 1 s healthy" % (what, 0.02 / dp),
           run.returncode == 0, run.stderr[-1500:])
    if run.returncode != 0:
        return
    mu_ratio = poiseuille_loaded.measure(folder)[1]
    change = mu_ratio / finest - 1
    print("mu_eq/mu0 = %.4f, %+.1f %% from the finest run's %.4f%s" % (mu_ratio, 100 * change, finest, note))
    report("%s: mu_eq/mu0 within %g %% of the finest run's" % (what, 100 * bound), abs(change) < bound,
           "%+.1f %%" % (100 * change))


def group_measured():
    dense_run("phi0.5_r3_measured", "measured film", 0.02 / 3, ["-s", "contacts.lubrication_tangential=sliding"],
              MEASURED_FINEST, MEASURED_BOUND,
              " (the cut-off model at r/dp 3: %.4f, %+.1f %%)" % (CUTOFF_R3, 100 * (CUTOFF_R3 / MEASURED_FINEST - 1)))


def group_tangential():
    tangential = ["-s", "contacts.lubrication_tangential=reynolds"]
    dense_run("phi0.5_r4_tangential", "tangential film", 0.005, tangential, TANGENTIAL_FINEST, TANGENTIAL_BOUND)
    hashes = []
    for threads in ("1", "2"):  # the films' rows are summed in list order: the same state on any thread count
        cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o",
               os.path.join(out, "threads" + threads), "--overwrite", "-s", "numerics.dp_m=%r" % (0.02 / 3),
               "-s", "boulders.solid_fraction=0.5", "-s", "numerics.scheme=implicit", "-s", "boulders.pack_fluid=true",
               "-s", "contacts.lubrication_resolved=measured", "-s", "time.end_s=0.3",
               "-s", "output.progress_interval_s=0", "--threads", threads] + tangential
        run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        found = re.search(r"state hash ([0-9a-f]+)", run.stdout + run.stderr)
        hashes.append(found.group(1) if run.returncode == 0 and found else None)
    report("tangential film: r/dp 3, 0.3 s, the same state hash on 1 and 2 threads (%s)" % hashes,
           hashes[0] is not None and hashes[0] == hashes[1])


def group_share():
    poiseuille_loaded.WINDOW_S = (0.2, 0.3)  # steady from about 0.1 s
    films = ["-s", "contacts.lubrication_resolved=measured", "-s", "contacts.lubrication_tangential=reynolds"]
    values = {}
    for name, scheme, share in (("explicit", "explicit", "scheme"), ("implicit", "implicit", "scheme"),
                                ("implicit_explicit_share", "implicit", "explicit")):
        folder = os.path.join(out, name)
        cmd = [surge, "run", os.path.join(root, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
               "-s", "numerics.dp_m=0.006666666666666667", "-s", "boulders.solid_fraction=0.5", "-s", "boulders.seed=1",
               "-s", "numerics.scheme=" + scheme, "-s", "contacts.lubrication_share=" + share, "-s", "time.end_s=0.3",
               "-s", "output.snapshot_interval_s=0.02", "-s", "output.progress_interval_s=0", "--threads", "1"] + films
        run = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
        report("%s scheme, %s share: the loaded channel at phi 0.5, r/dp 3 runs 0.3 s healthy" % (scheme, share),
               run.returncode == 0, run.stderr[-1500:])
        if run.returncode == 0:
            values[name] = poiseuille_loaded.measure(folder)[1]
            print("%s scheme, %s share: mu_eq/mu0 = %.4f" % (scheme, share, values[name]))
    if len(values) == 3:
        same = values["implicit_explicit_share"] / values["explicit"] - 1
        own = values["implicit"] / values["explicit"] - 1
        report("implicit with the explicit share within 8 % of the explicit scheme", abs(same) < 0.08,
               "%+.1f %%" % (100 * same))
        report("implicit with its own share at least 20 % above the explicit scheme", own > 0.20,
               "%+.1f %%" % (100 * own))


{"dilute": group_dilute, "kicks": group_kicks, "packing": group_packing, "schemes": group_schemes,
 "measured": group_measured, "tangential": group_tangential, "share": group_share}[group]()
print("%d check(s) failed" % failures if failures else "all checks passed")
sys.exit(1 if failures else 0)
