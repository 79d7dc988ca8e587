#!/usr/bin/python3
"""A disc settling onto the bed: how fast it closes the gap, against the squeeze film's own speed, and where the
SPH's pressure force on it comes from (docs/boulders.md, "Lubrication").

  build/surge run cases/boulder_settling.ini -o RUN_DIR -s numerics.dp_m=DP -s "boulders.list_m=0.05 0.01875 0.0125" \\
      [-s contacts.lubrication=1] -s time.end_s=6 -s output.snapshot_interval_s=0.02 --threads 1
  studies/boulders/disc_on_bed.py measure RUN_DIR

For each gap h/a in 0.4, 0.2, 0.1, 0.05 and 0.02 (the first snapshot at or below it) it prints the approach speed U
(from the disc's heights, centred differences), the film's own speed W / (3 sqrt(2) pi mu (a/h)^(3/2)) for the disc's
buoyant weight W = (rho_disc - rho) g pi a^2, their ratio, and the vertical pressure force of the SPH pair sums on
the disc's particles (eq. 10's pressure term, -m (p_a + p_k)/(rho_a rho_k) grad W summed over its fluid neighbours),
and the same sum over the bed's particles within reach: the support the bed takes out of the disc's kernels, whose
pressure acts on the disc with contacts.solid_pressure (on by default; "acts: no" where the run had it off). The run's
first disc is the one measured; the bed is y = 0.

  build/surge run cases/boulder_settling.ini -o RUN_DIR -s numerics.dp_m=a/K -s "boulders.list_m=0.05 0.0375 0.0125" \\
      -s numerics.ch=1.8 -s contacts.lubrication=0 -s time.end_s=8 -s output.snapshot_interval_s=0.02 \\
      [-s numerics.scheme=implicit] --threads 1
  studies/boulders/disc_on_bed.py share RUN_DIR

The share of the exact resistance the scheme resolves with the films off (contacts.lubrication_resolved = measured
adds the rest, docs/boulders.md): the disc's buoyant weight over its approach speed, interpolated at gaps 0.125 h
apart, over the resistance of a cylinder approaching a plane in Stokes flow, 4 pi mu / (alpha - tanh alpha) with
cosh alpha = 1 + h/a (Jeffrey & Onishi 1981). The disc starts 2a above the bed; at gaps above about 0.7 a the box's
walls add their drag.

  build/surge run cases/boulder_settling.ini -o RUN_DIR -s numerics.dp_m=a/K \\
      -s "boulders.list_m=0.05 0.0628 0.0125, 0.05 0.0128 0.0125" -s numerics.ch=1.8 -s contacts.lubrication=0 \\
      -s time.end_s=30 -s output.snapshot_interval_s=0.05 [-s numerics.scheme=implicit] --threads 1
  studies/boulders/disc_on_bed.py share RUN_DIR --onto disc

The same between two discs: the first disc settles onto the second, which rests on the bed. The gap is the one
between their surfaces along the line of centres, U the speed at which it closes, and the exact resistance the
plane's with the reduced radius R = r1 r2 / (r1 + r2) for a, as the films take it (exact at small gaps, where the
film's force is that of the plane's with R; at gaps near R it is the films' model, not Stokes' two-disc solution).

  build/surge run cases/boulder_settling.ini -o RUN_DIR -s numerics.dp_m=DP -s numerics.scheme=implicit -s numerics.ch=1.8 \\
      -s contacts.lubrication=0 -s domain.periodic_x=true -s walls.left=false -s walls.right=false \\
      -s domain.length_m=2L -s fluid.x1_m=2L -s domain.height_m=0.1 -s fluid.depth_m=0.1 \\
      -s "boulders.list_m=L/2 0.05 0.0125, 3L/2 0.05 0.0125" -s time.end_s=4 --threads 1
  studies/boulders/disc_on_bed.py row RUN_DIR

A periodic row of discs (two a period, L apart, gap s = L - 2a) settling mid-height: the fluid the row displaces
must pass through the gaps between discs that do not approach each other. It prints the row's resistance W/U over
0.5-1, 1-2, 2-3 and 3-4 s against the slot's lubrication resistance (9 pi / 2) mu L^2 sqrt(a) / s^(5/2) per disc
(Reynolds' equation through the gap h(x) = s + x^2 / a, flux U L; docs/validation/poiseuille_loaded.md, "Flow
through a gap").

  build/surge run cases/boulder_couette.ini -o RUN_DIR -s numerics.dp_m=a/K -s "boulders.list_m=0.1 a+g 0.0125" \\
      -s numerics.scheme=implicit -s numerics.ch=1.8 -s contacts.lubrication_resolved=measured -s time.end_s=3 --threads 1
  studies/boulders/disc_on_bed.py sheared RUN_DIR

A free disc a gap g above the moving bed of the Couette channel (bed and lid at -U and +U, shear rate 2U/H): how
fast it moves over the bed and turns, over the snapshots from 1.5 s on, as (V - u_bed)/(shear a) and omega/shear,
with its gap over a; the tangential films between a disc and a wall set them (docs/validation/poiseuille_loaded.md,
"The wall layer and the tangential film").

  build/surge run cases/boulder_couette.ini -o RUN_DIR -s numerics.dp_m=a/K -s walls.bottom_speed_mps=0 \
      -s walls.top_speed_mps=0 -s boulders.placement=file -s boulders.file=SPIN_CSV -s boulders.density_ratio=10000 \
      -s numerics.scheme=implicit -s numerics.ch=1.8 -s contacts.lubrication=false -s time.end_s=1 \
      -s output.snapshot_interval_s=0.05 -s implicit.viscous_tolerance=1e-10 --threads 1
  studies/boulders/disc_on_bed.py spin RUN_DIR

A heavy disc given a spin (SPIN_CSV: the header x_m,y_m,r_m,vx_mps,vy_mps,omega_radps and one row, e.g.
0.1,a+g,0.0125,0,0,1) a gap g above the bed of the channel with its walls at rest: the fluid's resistance to its
turning, R = I k with I = m a^2 / 2 and k = -d ln omega / dt fitted over the snapshots from 0.3 to 1 s (heavy enough
that the flow around it is steady as it slows, and that it barely moves: its largest speed over a omega is
printed), as R / (4 pi mu a^2) and over the exact resistance of a cylinder turning beside a plane in unbounded Stokes
flow, 4 pi mu a^2 coth alpha with cosh alpha = 1 + g/a (Jeffery 1922), with the gap over the kernel's h.

  studies/boulders/disc_on_bed.py slide RUN_DIR

The same for a heavy disc given a speed along the bed (SPIN_CSV's row e.g. 0.1,a+g,0.0125,0.0125,0,0): R = m k over
4 pi mu, k from its x speed's decay, with coth alpha - 1 (the tangential film's strength over 4 pi mu, its exact
value at contact; docs/boulders.md) and its largest a omega over its speed.
"""
import argparse
import os
import sys

import numpy as np

from surgepy import cli_checks, study, vtp
from surgepy.run_params import RunParams

TOOL = "disc_on_bed"
GAPS = (0.4, 0.2, 0.1, 0.05, 0.02)
KIND_FLUID, KIND_DISC = 0, 3


def fail(message):
    study.fail(TOOL, message)


def pressure_force_y(points, pressure, rho, disc, others, h, mass):
    """The vertical force on the disc's particles from the pair pressure terms with the particles `others`."""
    alpha = 7.0 / (4.0 * np.pi * h * h)
    grad_coef = -5.0 * alpha / (h * h)
    total = 0.0
    for k in disc:
        r = points[others] - points[k]
        dist = np.hypot(r[:, 0], r[:, 1])
        near = (dist > 0) & (dist < 2 * h)
        o, r, dist = others[near], r[near], dist[near]
        grad = grad_coef * (1 - 0.5 * dist / h) ** 3
        coef = -mass * (pressure[o] + pressure[k]) / (rho[o] * rho[k])
        total -= mass * np.sum(coef * grad * r[:, 1])  # minus the force on the neighbours
    return total


def disc_track(folder, what, least):
    """The disc files' times, the first `least` discs' centres (time, disc, xy) and each file's radii; ValueError
    naming the file where the run has fewer than 3 disc files or a file fewer than `least` discs."""
    discs = vtp.read_pvd(os.path.join(folder, "boulders.pvd"))
    if len(discs) < 3:
        raise ValueError("%s: boulders.pvd lists %d disc files; %s needs at least 3" % (folder, len(discs), what))
    times, points, radii = [], [], []
    for t, name in discs:
        d = vtp.read_vtp(os.path.join(folder, name), ("radius_m",), finite=True)
        if len(d["radius_m"]) < least:
            raise ValueError("%s: %s holds %d disc(s); %s" % (folder, name, len(d["radius_m"]),
                             "no disc to measure" if least == 1 else "%s needs %d" % (what, least)))
        times.append(t)
        points.append(d["points"][:least, :2].astype(float))
        radii.append(d["radius_m"])
    return np.array(times), np.array(points), radii


def measure(folder):
    params = RunParams(folder)
    dp, ch = params.positive("numerics", "dp_m"), params.positive("numerics", "ch")
    rho0, nu = params.positive("fluid", "density_kgpm3"), params.positive("fluid", "viscosity_m2ps")
    ratio, g = params.positive("boulders", "density_ratio"), params.positive("body", "gravity_mps2")
    h = ch * np.sqrt(2.0) * dp
    mass = rho0 * dp * dp
    times, points, radii = disc_track(folder, "the approach speed", 1)
    snaps = dict(vtp.read_pvd(os.path.join(folder, "run.pvd")))
    heights, radius = points[:, 0, 1], float(radii[-1][0])
    gaps = heights - radius
    speeds = -np.gradient(heights, times)
    weight = (ratio - 1.0) * rho0 * g * np.pi * radius * radius
    mu = rho0 * nu
    rows = []
    for target in GAPS:
        reached = np.nonzero(gaps <= target * radius)[0]
        if len(reached) == 0:
            rows.append((target, None))
            continue
        k = int(reached[0])
        film = weight / (3.0 * np.sqrt(2.0) * np.pi * mu * (radius / max(gaps[k], 1e-12 * radius)) ** 1.5)
        fluid_fy = wall_fy = float("nan")
        snap = min(snaps, key=lambda t: abs(t - times[k])) if snaps else None
        if snap is not None and abs(snap - times[k]) < 1e-9 + 1e-6 * abs(times[k]):
            s = vtp.read_vtp(os.path.join(folder, snaps[snap]), ("kind", "pressure_pa", "density_kgpm3"), finite=True)
            kind = s["kind"]
            points = s["points"][:, :2].astype(float)
            pressure, rho = s["pressure_pa"].astype(float), s["density_kgpm3"].astype(float)
            disc = np.nonzero(kind == KIND_DISC)[0]
            if len(disc) == 0:
                raise ValueError("%s: %s holds no disc particles (kind %d)" % (folder, snaps[snap], KIND_DISC))
            fluid = np.nonzero(kind == KIND_FLUID)[0]
            walls = np.nonzero((kind != KIND_FLUID) & (kind != KIND_DISC))[0]
            fluid_fy = pressure_force_y(points, pressure, rho, disc, fluid, h, mass)
            wall_fy = pressure_force_y(points, pressure, rho, disc, walls, h, mass)
        rows.append((target, (gaps[k] / radius, times[k], speeds[k], film, fluid_fy, wall_fy)))
    return weight, rows


SHARE_STEP_H = 0.125  # the gaps over the kernel's h at which `share` reads the resistance (lubrication.c's table)


def exact_resistance(mu, radius, gap):
    """A cylinder approaching a plane in Stokes flow, per unit speed and width: 4 pi mu / (alpha - tanh alpha),
    cosh alpha = 1 + gap/radius (Jeffrey & Onishi 1981)"""
    alpha = np.arccosh(1.0 + gap / radius)
    return 4.0 * np.pi * mu / (alpha - np.tanh(alpha))


def resolved_share(folder, onto="bed"):
    """The share of the exact resistance the scheme resolves at each gap the settling disc passed: (h, rows of
    (gap/h, gap/dp, share, t)) at the gaps SHARE_STEP_H apart, share = (W/U)/exact, U the speed at which the gap
    closes (centred differences) interpolated linearly in the gap. onto "bed": the first disc's gap to y = 0 and the
    exact resistance with its radius; "disc": its gap to the second disc along the line of centres and the reduced
    radius. ValueError naming the folder where the disc never approaches, or where onto is "disc" and the run has one
    disc."""
    params = RunParams(folder)
    dp, h = params.positive("numerics", "dp_m"), params.derived("h_m")
    mu = params.positive("fluid", "density_kgpm3") * params.positive("fluid", "viscosity_m2ps")
    ratio, g = params.positive("boulders", "density_ratio"), params.positive("body", "gravity_mps2")
    times, points, radii = disc_track(folder, "the resolved share", 2 if onto == "disc" else 1)
    radius = float(radii[-1][0])
    if onto == "disc":
        other = float(radii[-1][1])
        centres = np.hypot(points[:, 0, 0] - points[:, 1, 0], points[:, 0, 1] - points[:, 1, 1])
        gaps, film_radius = centres - radius - other, radius * other / (radius + other)
    else:
        gaps, film_radius = points[:, 0, 1] - radius, radius
    speeds = -np.gradient(gaps, times)
    weight = (ratio - 1.0) * params.positive("fluid", "density_kgpm3") * g * np.pi * radius * radius
    closing = speeds > 0
    if not closing.any():
        raise ValueError("%s: the disc never approaches the %s" % (folder, "second disc" if onto == "disc" else "bed"))
    rows = []
    for k in range(1, 1 + int(gaps[0] / h / SHARE_STEP_H)):
        target = k * SHARE_STEP_H * h
        crossed = np.nonzero((gaps[:-1] >= target) & (gaps[1:] < target) & closing[:-1] & closing[1:])[0]
        if not len(crossed):
            continue
        j = int(crossed[0])
        w = (gaps[j] - target) / (gaps[j] - gaps[j + 1])
        speed, t = (1 - w) * speeds[j] + w * speeds[j + 1], (1 - w) * times[j] + w * times[j + 1]
        rows.append((target / h, target / dp, weight / speed / exact_resistance(mu, film_radius, target), t))
    return h, rows


ROW_WINDOWS_S = ((0.5, 1.0), (1.0, 2.0), (2.0, 3.0), (3.0, 4.0))


def settling_row(folder):
    """The row's resistance W/U per window and the slot's lubrication resistance, from the first two discs."""
    params = RunParams(folder)
    rho0, nu = params.positive("fluid", "density_kgpm3"), params.positive("fluid", "viscosity_m2ps")
    ratio, g = params.positive("boulders", "density_ratio"), params.positive("body", "gravity_mps2")
    times, points, radii = disc_track(folder, "a row (two a period)", 2)
    heights, spacing, radius = points[:, 0, 1], abs(float(points[0, 1, 0] - points[0, 0, 0])), float(radii[0][0])
    gap = spacing - 2.0 * radius
    if not gap > 0:
        raise ValueError("%s: the first two discs are %.4g m apart, not more than a diameter (%.4g m)" %
                         (folder, spacing, 2.0 * radius))
    speeds = -np.gradient(heights, times)
    weight = (ratio - 1.0) * rho0 * g * np.pi * radius * radius
    slot = 4.5 * np.pi * rho0 * nu * spacing ** 2 * np.sqrt(radius) / gap ** 2.5
    windows = []
    for t0, t1 in ROW_WINDOWS_S:
        inside = (times >= t0) & (times <= t1)
        mean = float(np.mean(speeds[inside])) if inside.any() else float("nan")
        windows.append((t0, t1, weight / mean if mean > 0 else float("nan")))
    return radius, spacing, gap, slot, windows


SHEARED_FROM_S = 1.5


def sheared_disc(folder):
    """(samples, gap over a, (V - u_bed)/(shear a), omega/shear) of the run's first disc from SHEARED_FROM_S on;
    ValueError naming the folder where the channel is not sheared or no disc file is that late."""
    params = RunParams(folder)
    height = params.positive("domain", "height_m")
    bed, lid = params.real("walls", "bottom_speed_mps"), params.real("walls", "top_speed_mps")
    shear = (lid - bed) / height
    if shear == 0:
        raise ValueError("%s: walls.bottom_speed_mps = walls.top_speed_mps = %g m/s: the channel is not sheared"
                         % (params.path, bed))
    gaps, speeds, spins = [], [], []
    for t, name in vtp.read_pvd(os.path.join(folder, "boulders.pvd")):
        if t < SHEARED_FROM_S - 1e-9:
            continue
        d = vtp.read_vtp(os.path.join(folder, name), ("velocity_mps", "omega_radps", "radius_m"), finite=True)
        if not len(d["radius_m"]):
            raise ValueError("%s: %s holds no disc" % (folder, name))
        radius = float(d["radius_m"][0])
        gaps.append((float(d["points"][0, 1]) - radius) / radius)
        speeds.append((float(d["velocity_mps"][0, 0]) - bed) / (shear * radius))
        spins.append(float(d["omega_radps"][0]) / shear)
    if not gaps:
        raise ValueError("%s: no disc file from %g s on" % (folder, SHEARED_FROM_S))
    return len(gaps), float(np.mean(gaps)), float(np.mean(speeds)), float(np.mean(spins))


HEAVY_DISC_WINDOW_S = (0.3, 1.0)


def heavy_disc_resistance(folder, motion):
    """A heavy disc's resistance from the decay of its `motion` ("spin": its spin, "slide": its x speed) over
    HEAVY_DISC_WINDOW_S: (samples, gap over a, gap over the kernel's h, R, coth alpha, the other motion's largest size over
    the decaying one's first), R = I k over 4 pi mu a^2 (spin) or m k over 4 pi mu (slide), k = -d ln|.|/dt; the other
    motion is a V / omega (spin) or a omega / V (slide). ValueError naming the folder where the motion is zero,
    changes sign or grows, or fewer than 3 files lie in the window."""
    params = RunParams(folder)
    rho = params.positive("fluid", "density_kgpm3")
    mu = rho * params.positive("fluid", "viscosity_m2ps")
    ratio, h_kernel = params.positive("boulders", "density_ratio"), params.derived("h_m")
    times, values, others, gaps, radius = [], [], [], [], None
    for t, name in vtp.read_pvd(os.path.join(folder, "boulders.pvd")):
        d = vtp.read_vtp(os.path.join(folder, name), ("velocity_mps", "omega_radps", "radius_m"), finite=True)
        if not len(d["radius_m"]):
            raise ValueError("%s: %s holds no disc" % (folder, name))
        radius = float(d["radius_m"][0])
        spin, speed = float(d["omega_radps"][0]), float(d["velocity_mps"][0, 0])
        others.append(abs(radius * spin) if motion == "slide" else float(np.hypot(*d["velocity_mps"][0, :2])))
        if HEAVY_DISC_WINDOW_S[0] - 1e-9 <= t <= HEAVY_DISC_WINDOW_S[1] + 1e-6:
            times.append(t)
            values.append(spin if motion == "spin" else speed)
            gaps.append(float(d["points"][0, 1]) - radius)
    if len(times) < 3:
        raise ValueError("%s: %d disc files between %g and %g s; the fit needs 3" % (folder, len(times), *HEAVY_DISC_WINDOW_S))
    values = np.array(values)
    what = "spin" if motion == "spin" else "x speed"
    if not (np.all(values > 0) or np.all(values < 0)):
        raise ValueError("%s: the disc's %s is zero or changes sign between %g and %g s: no decay to measure"
                         % (folder, what, *HEAVY_DISC_WINDOW_S))
    decay = -np.polyfit(times, np.log(np.abs(values)), 1)[0]
    if decay <= 0:
        raise ValueError("%s: the disc's %s does not decay between %g and %g s (d ln|.|/dt = %.3g 1/s)"
                         % (folder, what, *HEAVY_DISC_WINDOW_S, -decay))
    gap = float(np.mean(gaps))
    if gap <= 0:
        raise ValueError("%s: the disc's surface is at or below the bed (gap %.3g m)" % (folder, gap))
    mass = ratio * rho * np.pi * radius ** 2
    if motion == "spin":
        resistance = 0.5 * mass * radius ** 2 * decay / (4 * np.pi * mu * radius ** 2)
        first = radius * abs(values[0])
    else:
        resistance = mass * decay / (4 * np.pi * mu)
        first = abs(values[0])
    return (len(times), gap / radius, gap / h_kernel, resistance, 1 / np.tanh(np.arccosh(1 + gap / radius)),
            max(others) / first)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    meas = sub.add_parser("measure")
    meas.add_argument("run_dir", type=cli_checks.folder)
    row_parser = sub.add_parser("row")
    row_parser.add_argument("run_dir", type=cli_checks.folder)
    sub.add_parser("sheared").add_argument("run_dir", type=cli_checks.folder)
    sub.add_parser("spin").add_argument("run_dir", type=cli_checks.folder)
    sub.add_parser("slide").add_argument("run_dir", type=cli_checks.folder)
    share_parser = sub.add_parser("share")
    share_parser.add_argument("run_dir", type=cli_checks.folder)
    share_parser.add_argument("--onto", choices=("bed", "disc"), default="bed",
                              help="the gap measured: the first disc's to the bed (y = 0) or to the second disc")
    args = parser.parse_args()
    if args.command == "share":
        try:
            h, rows = resolved_share(args.run_dir, args.onto)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("kernel h = %.4g m; the resistance resolved (W/U) over the exact 4 pi mu/(alpha - tanh alpha)%s"
              % (h, ", the reduced radius for a" if args.onto == "disc" else ""))
        print("gap/h   gap/dp   share    t (s)")
        for gap_h, gap_dp, share, t in rows:
            print("%-6.3f  %-6.3f  %6.3f  %7.3f" % (gap_h, gap_dp, share, t))
        return 0
    if args.command in ("spin", "slide"):
        try:
            samples, gap, gap_h, resistance, coth, drift = heavy_disc_resistance(args.run_dir, args.command)
        except (OSError, ValueError) as e:
            fail(str(e))
        if args.command == "spin":
            print("%d disc files from %g to %g s: gap/a %.4f, gap/h %.3f, R/(4 pi mu a^2) %.4f, exact coth alpha %.4f, "
                  "R/exact %.4f; largest speed/(a omega) %.1e" % (samples, *HEAVY_DISC_WINDOW_S, gap, gap_h, resistance,
                                                                 coth, resistance / coth, drift))
        else:
            print("%d disc files from %g to %g s: gap/a %.4f, gap/h %.3f, R/(4 pi mu) %.4f, coth alpha - 1 %.4f; "
                  "largest a omega/speed %.1e" % (samples, *HEAVY_DISC_WINDOW_S, gap, gap_h, resistance, coth - 1, drift))
        return 0
    if args.command == "sheared":
        try:
            samples, gap, speed, spin = sheared_disc(args.run_dir)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("%d disc files from %g s: gap/a %.4f, (V - u_bed)/(shear a) %.4f, omega/shear %.4f"
              % (samples, SHEARED_FROM_S, gap, speed, spin))
        return 0
    if args.command == "row":
        try:
            radius, spacing, gap, slot, windows = settling_row(args.run_dir)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("a = %.4g m, L = %.4g m, gap s = %.4g m (s/a %.3f); slot's lubrication resistance %.4g N s m^-2" %
              (radius, spacing, gap, gap / radius, slot))
        for t0, t1, resistance in windows:
            print("%.1f-%.1f s   W/U = %.4g N s m^-2   over the slot's %.3f" % (t0, t1, resistance, resistance / slot))
        return 0
    try:
        weight, rows = measure(args.run_dir)
        solid = RunParams(args.run_dir).flag("contacts", "solid_pressure", False)  # absent: a run from before the key
    except (OSError, ValueError) as e:
        fail(str(e))
    print("buoyant weight W = %.4g N/m" % weight)
    print("h/a      t (s)   U (m/s)     film (m/s)  U/film   SPH pressure Fy: fluid (N/m)  bed particles (acts: %s)"
          % ("yes" if solid else "no"))
    for target, row in rows:
        if row is None:
            print("%-6.2f   not reached" % target)
            continue
        gap, t, speed, film, fluid_fy, wall_fy = row
        print("%-6.3f   %6.2f  %.3e   %.3e   %7.2f  %12.3f                  %8.3f" %
              (gap, t, speed, film, speed / film, fluid_fy, wall_fy))
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
