#!/usr/bin/python3
"""The loaded-Poiseuille viscosity test (GMD paper Sect. 3.2, Table 2): a sweep over the solid fraction phi of
cases/poiseuille_loaded.ini, each run in its own folder and resumable from checkpoints, one CSV row per finished
run; `report` fits Krieger-Dougherty to mu_eq/mu0(phi) and plots it with the Einstein-Brady line.

  studies/poiseuille_loaded/poiseuille_loaded.py run [--phi 0,0.05,0.1,0.2,0.3,0.4,0.5] [--dp 0.0066667] [--ch 1.8]
        [--seed 1] [--c0 M_PER_S (0: derived)] [--diffusion DELTA (default: the case's)] [--threads 2]
        [--scheme explicit|implicit] [--lubrication [--cutoff-dp 1] [--resolved cutoff|measured]
        [--tangential sliding|reynolds]] [--pack-fluid] [--budget-s SECONDS]
        [--runs-dir runs/poiseuille_loaded] [--csv studies/poiseuille_loaded/data/poiseuille_loaded.csv]
  studies/poiseuille_loaded/poiseuille_loaded.py add RUN_DIR [--wall-s S] [--threads N] [--csv ...]
        # a finished run made by hand (surge run cases/poiseuille_loaded.ini ...) measured into the table
  studies/poiseuille_loaded/poiseuille_loaded.py measure RUN_DIR      # u_max and mu_eq/mu0 of one finished run
  studies/poiseuille_loaded/poiseuille_loaded.py discs RUN_DIR        # how the discs move against the flow
  studies/poiseuille_loaded/poiseuille_loaded.py shells RUN_DIR       # how the fluid packs beside the discs
  studies/poiseuille_loaded/poiseuille_loaded.py layers RUN_DIR [RUN_DIR ...] [--band-m 0.01]
        # where across the channel the centre speed is gained, run beside run
  studies/poiseuille_loaded/poiseuille_loaded.py reference [--phi ...] [--seed 1]   # dilute theory for the placed discs
  studies/poiseuille_loaded/poiseuille_loaded.py report [--csv ...] [--png docs/validation/poiseuille_loaded.png]
        [--dp DP] [--c0 C0] [--diffusion DELTA] [--scheme explicit|implicit]
        [--lubrication [--cutoff-dp 1] [--resolved cutoff|measured] [--tangential sliding|reynolds]] [--pack-fluid]
        [--seed 1]
  studies/poiseuille_loaded/poiseuille_loaded.py convergence [--csv ...] [--png PNG] [--scheme implicit|explicit]
        [--c0 C0] [--diffusion DELTA] [--seed 1] [--ch 1.8] [--models none,cutoff,measured,reynolds]
        [--placement both|packed|default]   # mu_eq/mu0 per phi and r/dp, per lubrication model and placement
  studies/poiseuille_loaded/poiseuille_loaded.py seeds [--csv ...] [--scheme implicit|explicit] [--c0 C0]
        [--diffusion DELTA] [--lubrication [--cutoff-dp 1] [--resolved cutoff|measured] [--tangential sliding|reynolds]]
        [--pack-fluid]   # mu_eq/mu0 per phi and r/dp over the placements (seeds) run

Measurement (docs/references.md section 4, eq. 19): u_max is the mean x velocity of the fluid particles within 1 cm of
the centre line, over every snapshot with 0.8 <= t <= 1 s; mu_eq = B^2 rho |dP/dx| / (8 u_max) with the driving
body force F = |dP/dx| / rho, and mu0 = rho nu0. phi_actual is the placed disc area over L B.
`discs`: over the same snapshots, each disc's x speed less the fluid's at its height (a parabola fitted to every fluid
particle's x speed against y), over the parabola's centre speed, and its spin over half the parabola's vorticity
at its height, -u'(y)/2 (a torque-free disc's in Stokes flow); prints the samples, the mean and spread of the lag and
the median spin ratio.
`shells`: over the same snapshots, the fluid's number density at each distance from a disc's face (bins of 0.1 dp
out to 2 dp; the count in the annulus over its area times 1/dp^2, the lattice's density), over every disc whose
annulus stays clear of the plates; 1 is the lattice's density, a shell of particles shows as a peak.
`layers`: over the same snapshots, the mean x velocity of the mixture in bands by the distance from the nearer plate
(the two halves folded together): each fluid particle weighs dp^2, each disc is sampled on a grid of dp/2 moving
rigidly (V - omega y'). Between neighbouring bands the local viscosity is the shear stress over the shear rate,
rho F (B/2 - y) / (du/dy), over mu0; a band average of a parabola differs from its centre value by the same amount
in every band, so a clear channel reads 1 exactly. Then, per run, the speed gained from the plates to two radii of
the largest disc (the layer of the discs that touch a plate) and from there to the centre: where one resolution's
centre speed differs from another's.
The fit minimises the squared error of mu_eq/mu0 over (phi_m, p) of (1 - phi/phi_m)^(-p phi_m) (coarse grid,
then finer grids around the best point); RMSE = sqrt(mean((mu_eq/mu0 - fit)^2)) as in the paper's eq. 20.
--scheme sets numerics.scheme, --lubrication contacts.lubrication (with --cutoff-dp its cut-off,
contacts.lubrication_cutoff_dp, --resolved contacts.lubrication_resolved and --tangential
contacts.lubrication_tangential) and --pack-fluid boulders.pack_fluid for
the runs; `add` reads them, and every other
setting the table records, from the run folder's params.ini. `report` takes the rows of one scheme, with or without
the lubrication model (default: explicit, without; --cutoff-dp its cut-off), at the default placement of the fluid
or (--pack-fluid) packed. `convergence` takes one placement (--seed,
default 1) at every resolution; `seeds` gives, per phi and r/dp, each seed's mu_eq/mu0, their mean and standard
deviation, and the change of the mean from the next coarser r/dp run with at least two seeds, with its standard
error (the two means' standard errors combined, over the coarser mean).

Reference (dilute theory for the discs actually placed): the placement depends only on phi and the seed, not on
dp, so `reference` places them (a run of one step at dp = r/2) and integrates the steady momentum balance across
the channel with the local Einstein-Brady viscosity mu(y) = mu0 (1 + 2 phi(y)), phi(y) the discs' area fraction
at height y (their chords over L), u(y) from the shear stress rho F (y0 - y) with y0 where u(0) = u(B) = 0, u_max
its mean within 1 cm of the centre line, mu_eq from eq. 19 (clear fluid: 1.00037, from the band's mean). It counts
the discs' absence within r of the plates (where the shear is largest) and is valid where Einstein-Brady is (phi
up to about 0.1). One row per phi in studies/poiseuille_loaded/data/poiseuille_loaded_reference.csv.
"""
import argparse
import csv
import os
import subprocess
import sys
import time

import numpy as np

from surgepy import cli_checks, study, vtp
from surgepy.run_params import RunParams

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

TOOL = "poiseuille_loaded"
COLUMNS = ["phi", "phi_actual", "n_discs", "dp_m", "ch", "seed", "threads", "wall_s", "particle_steps", "sim_time_s",
           "u_max_mps", "mu_eq_over_mu0", "status", "c0_mps", "density_diffusion", "scheme", "lubrication",
           "lubrication_cutoff_dp", "pack_fluid", "lubrication_resolved", "lubrication_tangential"]
WINDOW_S = (0.8, 1.0)
PHI_M_MAX = 1.0  # a packing fraction above 1 means the data do not diverge: the fit says so instead
HALF_BAND_M = 0.01
SHELL_BINS, SHELL_BIN_DP = 20, 0.1
LAYER_BAND_M = 0.01
DILUTE_PHI = 0.1  # Einstein-Brady holds up to about here
RADIUS_M = 0.02  # the case's disc radius (boulders.radius_m): r/dp names a resolution
REFERENCE_CSV = os.path.join(ROOT, "studies", "poiseuille_loaded", "data", "poiseuille_loaded_reference.csv")
RUNS_CSV = os.path.join(ROOT, "studies", "poiseuille_loaded", "data", "poiseuille_loaded.csv")


def fail(message):
    study.fail(TOOL, message)


def measure(folder):
    """(u_max, mu_eq/mu0, phi_actual, n_discs) of a finished run; ValueError (ParamsError, VtpError) naming the file
    and what is wrong where the run cannot be measured."""
    params = RunParams(folder)
    rho, nu0 = params.positive("fluid", "density_kgpm3"), params.positive("fluid", "viscosity_m2ps")
    force, gap = params.real("body", "force_x_mps2"), params.positive("domain", "height_m")
    length = params.positive("domain", "length_m")
    speeds = []
    for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd")):
        if WINDOW_S[0] - 1e-9 <= t <= WINDOW_S[1] + 1e-6:
            path = os.path.join(folder, name)
            s = vtp.read_vtp(path, ("kind", "velocity_mps"), finite=True)
            band = (s["kind"] == 0) & (np.abs(s["points"][:, 1] - gap / 2) <= HALF_BAND_M)
            if not band.any():
                raise ValueError("%s: no fluid particle within %g m of the centre line" % (path, HALF_BAND_M))
            speeds.append(s["velocity_mps"][band, 0].astype(float).mean())
    if not speeds:
        raise ValueError("%s: no snapshot between %g and %g s" % (folder, *WINDOW_S))
    u_max = float(np.mean(speeds))
    if force == 0 or u_max == 0:
        raise ValueError("%s: [body] force_x_mps2 = %g and u_max = %g m/s: no driven flow to measure a viscosity by"
                         % (params.path, force, u_max))
    mu_ratio = gap * gap * rho * force / (8 * u_max) / (rho * nu0)
    radii = np.zeros(0)
    if os.path.isfile(os.path.join(folder, "boulders.pvd")):
        discs = vtp.read_pvd(os.path.join(folder, "boulders.pvd"))
        if discs:
            radii = vtp.read_vtp(os.path.join(folder, discs[0][1]), ("radius_m",))["radius_m"]
    return u_max, mu_ratio, float(np.sum(np.pi * radii ** 2) / (length * gap)), int(radii.size)


def disc_motion(folder):
    """(samples, mean lag, its standard deviation, median spin ratio) of the discs over the window (see the module's
    `discs`); ValueError naming the folder where it has no discs or no snapshot in the window."""
    fluid_at = {round(t, 9): name for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd"))}
    lags, spins = [], []
    for t, name in vtp.read_pvd(os.path.join(folder, "boulders.pvd")):
        if not (WINDOW_S[0] - 1e-9 <= t <= WINDOW_S[1] + 1e-6) or round(t, 9) not in fluid_at:
            continue
        discs = vtp.read_vtp(os.path.join(folder, name), ("velocity_mps", "omega_radps"), finite=True)
        s = vtp.read_vtp(os.path.join(folder, fluid_at[round(t, 9)]), ("kind", "velocity_mps"), finite=True)
        fluid = s["kind"] == 0
        profile = np.polyfit(s["points"][fluid, 1], s["velocity_mps"][fluid, 0].astype(float), 2)
        y = discs["points"][:, 1]
        centre_speed = np.polyval(profile, -profile[1] / (2 * profile[0]))
        lags.append((discs["velocity_mps"][:, 0] - np.polyval(profile, y)) / centre_speed)
        spins.append(discs["omega_radps"] / (-np.polyval(np.polyder(profile), y) / 2))
    if not lags or not np.concatenate(lags).size:
        raise ValueError("%s: no discs in a snapshot between %g and %g s" % (folder, *WINDOW_S))
    lag, spin = np.concatenate(lags), np.concatenate(spins)
    return lag.size, float(lag.mean()), float(lag.std()), float(np.median(spin))


def shell_density(folder, bins=SHELL_BINS, bin_dp=SHELL_BIN_DP):
    """(bin edges in dp from the discs' faces, the fluid's number density in each over the lattice's, annuli counted)
    over the window (see the module's `shells`); ValueError naming the folder where no disc in a snapshot in the window
    stays clear of the plates."""
    params = RunParams(folder)
    dp, gap = params.positive("numerics", "dp_m"), params.positive("domain", "height_m")
    length = params.positive("domain", "length_m")
    fluid_at = {round(t, 9): name for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd"))}
    edges = np.arange(bins + 1) * bin_dp
    counts, areas, annuli = np.zeros(bins), np.zeros(bins), 0
    for t, name in vtp.read_pvd(os.path.join(folder, "boulders.pvd")):
        if not (WINDOW_S[0] - 1e-9 <= t <= WINDOW_S[1] + 1e-6) or round(t, 9) not in fluid_at:
            continue
        discs = vtp.read_vtp(os.path.join(folder, name), ("radius_m",), finite=True)
        s = vtp.read_vtp(os.path.join(folder, fluid_at[round(t, 9)]), ("kind",), finite=True)
        fluid = s["points"][s["kind"] == 0, :2]
        for (cx, cy), r in zip(discs["points"][:, :2], discs["radius_m"]):
            outer = r + edges[-1] * dp
            if cy - outer < 0 or cy + outer > gap:
                continue
            dx = fluid[:, 0] - cx
            dx -= length * np.round(dx / length)
            counts += np.histogram((np.hypot(dx, fluid[:, 1] - cy) - r) / dp, bins=edges)[0]
            areas += np.pi * ((r + edges[1:] * dp) ** 2 - (r + edges[:-1] * dp) ** 2) / (dp * dp)
            annuli += 1
    if not annuli:
        raise ValueError("%s: no disc clear of the plates by %g dp in a snapshot between %g and %g s"
                         % (folder, edges[-1], *WINDOW_S))
    return edges, counts / areas


def local_einstein(centres_y, radius, length, gap):
    """mu_eq/mu0 that eq. 19 gives for a steady channel flow whose local viscosity is mu0 (1 + 2 phi(y))
    (Einstein-Brady, D = 2), phi(y) the area fraction at height y of discs of the given radius centred at centres_y
    (per period length), with u_max measured as the tool measures it (the mean within HALF_BAND_M of the centre)."""
    y = np.linspace(0, gap, 6001)
    phi_y = (2 * np.sqrt(np.clip(radius ** 2 - (y[:, None] - np.asarray(centres_y)[None, :]) ** 2, 0, None))).sum(1)
    fluidity = 1 / (1 + 2 * phi_y / length)
    # shear stress rho F (y0 - y) vanishes at y0, where u(0) = u(B) = 0 puts it; units rho F / mu0 = 1
    y0 = np.trapz(y * fluidity, y) / np.trapz(fluidity, y)
    slope = (y0 - y) * fluidity
    u = np.concatenate([[0], np.cumsum((slope[1:] + slope[:-1]) / 2 * np.diff(y))])
    return gap * gap / 8 / u[np.abs(y - gap / 2) <= HALF_BAND_M].mean()


def velocity_layers(folder, band_m=LAYER_BAND_M):
    """The mixture's mean x velocity over the window in bands of band_m by the distance from the nearer plate (see the
    module's `layers`): (band edges in m, u per band in m/s, the local mu/mu0 between neighbouring bands, the
    discs' largest radius in m); ValueError naming the folder where a band holds nothing or no snapshot is in the
    window."""
    params = RunParams(folder)
    dp, gap = params.positive("numerics", "dp_m"), params.positive("domain", "height_m")
    force, nu0 = params.real("body", "force_x_mps2"), params.positive("fluid", "viscosity_m2ps")
    edges = np.arange(0, gap / 2 + 1e-12, band_m)
    if edges.size < 3:
        raise ValueError("%s: a band of %g m leaves fewer than two bands across half the channel (%g m)"
                         % (folder, band_m, gap / 2))
    momentum, area = np.zeros(edges.size - 1), np.zeros(edges.size - 1)
    disc_at = {}
    if os.path.isfile(os.path.join(folder, "boulders.pvd")):
        disc_at = {round(t, 9): name for t, name in vtp.read_pvd(os.path.join(folder, "boulders.pvd"))}
    radius_max, snapshots = 0.0, 0

    def add(y, u, weight):
        folded = np.minimum(y, gap - y)
        momentum[:] += np.histogram(folded, edges, weights=u * weight)[0]
        area[:] += np.histogram(folded, edges, weights=np.broadcast_to(weight, np.shape(y)))[0]

    for t, name in vtp.read_pvd(os.path.join(folder, "run.pvd")):
        if not WINDOW_S[0] - 1e-9 <= t <= WINDOW_S[1] + 1e-6:
            continue
        s = vtp.read_vtp(os.path.join(folder, name), ("kind", "velocity_mps"), finite=True)
        fluid = s["kind"] == 0
        add(s["points"][fluid, 1], s["velocity_mps"][fluid, 0].astype(float), dp * dp)
        snapshots += 1
        if round(t, 9) not in disc_at:
            continue
        d = vtp.read_vtp(os.path.join(folder, disc_at[round(t, 9)]), ("velocity_mps", "omega_radps", "radius_m"),
                         finite=True)
        step = dp / 2  # each disc sampled on a grid of dp/2, moving rigidly
        for cy, vx, omega, r in zip(d["points"][:, 1], d["velocity_mps"][:, 0], d["omega_radps"], d["radius_m"]):
            offsets = np.arange(-r + step / 2, r, step)
            ox, oy = np.meshgrid(offsets, offsets)
            inside = oy[ox * ox + oy * oy < r * r]
            add(cy + inside, vx - omega * inside, step * step)
            radius_max = max(radius_max, float(r))
    if not snapshots:
        raise ValueError("%s: no snapshot between %g and %g s" % (folder, *WINDOW_S))
    if not np.all(area > 0):
        raise ValueError("%s: the band %g-%g m from the plates holds no fluid particle or disc"
                         % (folder, edges[np.argmin(area)], edges[np.argmin(area) + 1]))
    u = momentum / area
    centres = 0.5 * (edges[1:] + edges[:-1])
    stress = force * (gap / 2 - 0.5 * (centres[1:] + centres[:-1]))  # rho F (B/2 - y) over rho
    with np.errstate(divide="ignore"):
        mu_local = stress * np.diff(centres) / np.diff(u) / nu0
    return edges, u, mu_local, radius_max


REFERENCE_COLUMNS = ["phi", "seed", "phi_actual", "n_discs", "mu_local_einstein", "mu_uniform_einstein"]


def command_reference(args):
    rows = []
    for phi in args.phi:
        folder = os.path.join(args.runs_dir, "placement_phi%g_seed%d" % (phi, args.seed))
        argv = [args.surge, "run", os.path.join(ROOT, "cases", "poiseuille_loaded.ini"), "-o", folder,
                "--overwrite", "-s", "numerics.dp_m=0.01", "-s", "boulders.solid_fraction=%g" % phi, "-s", "boulders.seed=%d" % args.seed,
                "-s", "time.end_s=1e-6", "-s", "output.progress_interval_s=0", "--threads", "1"]
        if subprocess.run(argv, stdin=subprocess.DEVNULL, env=study.solver_environment()).returncode != 0:
            fail("placing the discs for phi = %g failed: %s" % (phi, " ".join(argv)))
        if not os.path.isdir(folder):
            fail("placing the discs for phi = %g: surge exited 0 but wrote no run in %s" % (phi, folder))
        try:  # ParamsError and VtpError are ValueErrors
            params = RunParams(folder)
            gap, length = params.real("domain", "height_m"), params.real("domain", "length_m")
            placed = vtp.read_pvd(os.path.join(folder, "boulders.pvd"))
            if not placed:
                fail("%s: no boulder snapshot listed" % os.path.join(folder, "boulders.pvd"))
            discs = vtp.read_vtp(os.path.join(folder, placed[0][1]), ("radius_m",), finite=True)
        except (OSError, ValueError) as e:
            fail("placing the discs for phi = %g: %s" % (phi, e))
        radii, centres_y = discs["radius_m"], discs["points"][:, 1]
        if radii.size == 0:
            fail("placing the discs for phi = %g: %s holds no disc" % (phi, placed[0][1]))
        if np.ptp(radii) > 0:
            fail("the reference assumes one radius; phi = %g placed radii %g-%g m" % (phi, radii.min(), radii.max()))
        phi_actual = float(np.sum(np.pi * radii ** 2) / (length * gap))
        row = {"phi": phi, "seed": args.seed, "phi_actual": "%.4f" % phi_actual, "n_discs": radii.size,
               "mu_local_einstein": "%.5f" % local_einstein(centres_y, radii[0], length, gap),
               "mu_uniform_einstein": "%.5f" % (1 + 2 * phi_actual)}
        rows.append(row)
        print("%s: reference %s" % (TOOL, row), flush=True)
    try:
        with open(args.csv, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=REFERENCE_COLUMNS)
            writer.writeheader()
            writer.writerows(rows)
    except OSError as e:
        fail("--csv: cannot write %s: %s" % (args.csv, e.strerror))
    print("%s: wrote %s" % (TOOL, args.csv))
    return 0


def case_diffusion():
    """delta of cases/poiseuille_loaded.ini (the registry's 0.1 where the case does not set it)."""
    return RunParams(os.path.join(ROOT, "cases", "poiseuille_loaded.ini")).real("numerics", "density_diffusion", 0.1)


def run_one(args, phi, deadline):
    name = "phi%g_dp%g_ch%g_seed%d%s%s%s%s" % (phi, args.dp, args.ch, args.seed, "_c0%g" % args.c0 if args.c0 else "",
                                              "_dd%g" % args.diffusion if args.diffusion >= 0 else "",
                                              "_implicit" if args.scheme == "implicit" else "",
                                              "_lubrication%g" % args.cutoff_dp if args.lubrication else "") + \
        ("_measured" if args.lubrication and args.resolved == "measured" else "") + \
        ("_reynolds" if args.lubrication and args.tangential == "reynolds" else "") + \
        ("_packed" if args.pack_fluid else "")
    folder = os.path.join(args.runs_dir, name)
    common = ["-s", "output.progress_interval_s=60", "--threads", str(args.threads)]
    fresh = [args.surge, "run", os.path.join(ROOT, "cases", "poiseuille_loaded.ini"), "-o", folder, "--overwrite",
             "-s", "numerics.dp_m=%.17g" % args.dp, "-s", "numerics.ch=%g" % args.ch, "-s", "boulders.seed=%d" % args.seed]
    fresh += ["-s", "boulders.solid_fraction=%g" % phi] if phi > 0 else ["-s", "boulders.placement=none"]
    fresh += ["-s", "numerics.c0_mps=%g" % args.c0] if args.c0 else []
    fresh += ["-s", "numerics.density_diffusion=%g" % args.diffusion] if args.diffusion >= 0 else []
    fresh += ["-s", "numerics.scheme=%s" % args.scheme, "-s", "contacts.lubrication=%s" % str(args.lubrication).lower(),
              "-s", "contacts.lubrication_cutoff_dp=%g" % args.cutoff_dp,
              "-s", "contacts.lubrication_resolved=%s" % args.resolved,
              "-s", "contacts.lubrication_tangential=%s" % args.tangential,
              "-s", "boulders.pack_fluid=%s" % str(args.pack_fluid).lower()]
    rc, progress = study.run_resumable("%s: %s" % (TOOL, name), folder, fresh, args.surge, common, deadline)
    if rc == 4:
        return False
    try:
        row = table_row(folder, args.threads, progress["wall_s"], rc == 0)
    except ValueError as e:  # ParamsError, VtpError, nothing to measure
        fail("%s: %s" % (name, e))
    if rc != 0:
        row["status"] = "exit %d (health monitor)" % rc if rc == 1 else "exit %d" % rc
    progress["status"] = row["status"]
    study.write_progress(folder, progress)
    study.append_row(args.csv, COLUMNS, row)
    print("%s: %s: %s" % (TOOL, name, row), flush=True)
    return True


def table_row(folder, threads, wall_s, finished):
    """The table's row of a run folder, its settings read from its params.ini; measured where finished (ValueError,
    naming the file, where it cannot be)."""
    params = RunParams(folder)
    steps, sim_time = study.particle_steps(TOOL, folder)
    lubrication = params.flag("contacts", "lubrication", False)
    phi = params.real("boulders", "solid_fraction") if params.word("boulders", "placement", "random") != "none" else 0
    row = {"phi": "%g" % phi, "dp_m": "%.6g" % params.positive("numerics", "dp_m"),
           "ch": "%g" % params.positive("numerics", "ch"), "seed": int(params.real("boulders", "seed")),
           "threads": threads, "wall_s": "%.1f" % wall_s, "u_max_mps": "nan", "mu_eq_over_mu0": "nan",
           "phi_actual": "nan", "n_discs": 0, "particle_steps": steps, "sim_time_s": "%.3f" % sim_time,
           "c0_mps": "%.4g" % params.derived("c0_mps"),
           "density_diffusion": "%g" % params.real("numerics", "density_diffusion"),
           "scheme": params.word("numerics", "scheme", "explicit"), "lubrication": int(lubrication),
           "lubrication_cutoff_dp": "%g" % params.real("contacts", "lubrication_cutoff_dp") if lubrication else "",
           "pack_fluid": int(params.flag("boulders", "pack_fluid", False)),
           "lubrication_resolved": params.word("contacts", "lubrication_resolved", "cutoff") if lubrication else "",
           "lubrication_tangential": params.word("contacts", "lubrication_tangential", "sliding") if lubrication else ""}
    if finished:
        u_max, mu_ratio, phi_actual, n_discs = measure(folder)
        row.update({"u_max_mps": "%.6g" % u_max, "mu_eq_over_mu0": "%.5g" % mu_ratio,
                    "phi_actual": "%.4f" % phi_actual, "n_discs": n_discs, "status": "ok"})
    return row


def command_add(args):
    """A finished run made by hand, measured into the table (its settings from its params.ini)."""
    study.existing_rows(TOOL, args.csv, COLUMNS, {})
    if not os.path.isfile(os.path.join(args.run_dir, "checkpoint.bin")):
        fail("%s: no checkpoint.bin: not a finished run" % args.run_dir)
    try:
        row = table_row(args.run_dir, args.threads, args.wall_s, True)
        end_s = RunParams(args.run_dir).real("time", "end_s")
    except (OSError, ValueError) as e:
        fail(str(e))
    if float(row["sim_time_s"]) < end_s - 1e-6:
        fail("%s: ran to %s s of its %g s: not finished" % (args.run_dir, row["sim_time_s"], end_s))
    study.append_row(args.csv, COLUMNS, row)
    print("%s: %s: %s" % (TOOL, args.run_dir, row), flush=True)
    return 0


def command_run(args):
    rows = study.existing_rows(TOOL, args.csv, COLUMNS, dict(
        phi=float, dp_m=float, ch=float, seed=int, c0_mps=str, density_diffusion=float, scheme=str, lubrication=int,
        lubrication_cutoff_dp=str, pack_fluid=int, lubrication_resolved=str, lubrication_tangential=str))
    deadline = time.time() + args.budget_s if args.budget_s else None
    diffusion = args.diffusion if args.diffusion >= 0 else case_diffusion()
    done = {(float(r["phi"]), float(r["dp_m"]), float(r["ch"]), int(r["seed"]), r["c0_mps"] if args.c0 else "",
             float(r["density_diffusion"]), r["scheme"], int(r["lubrication"]), r["lubrication_cutoff_dp"],
             int(r["pack_fluid"]), r["lubrication_resolved"], r["lubrication_tangential"]) for r in rows}
    for phi in args.phi:
        if (phi, float("%.6g" % args.dp), args.ch, args.seed, "%.4g" % args.c0 if args.c0 else "", diffusion,
                args.scheme, int(args.lubrication), "%g" % args.cutoff_dp if args.lubrication else "",
                int(args.pack_fluid), args.resolved if args.lubrication else "",
                args.tangential if args.lubrication else "") in done:
            continue
        if deadline and time.time() > deadline:
            print("%s: budget spent; run again to continue" % TOOL, flush=True)
            return 0
        if not run_one(args, phi, deadline):
            print("%s: interrupted; run again to continue" % TOOL, flush=True)
            return 0
    return 0


def krieger_dougherty(phi, phi_m, p):
    return (1 - phi / phi_m) ** (-p * phi_m)


def fit(phi, mu):
    """(phi_m, p, rmse) minimising sum (mu - KD)^2 over phi_m in (max phi, 1] and p in [0.1, 20]: a grid, then
    finer grids around the best point."""
    lo_m, hi_m, lo_p, hi_p = max(phi) + 1e-3, PHI_M_MAX, 0.1, 20.0
    best = None
    for _ in range(6):
        grid_m, grid_p = np.linspace(lo_m, hi_m, 121), np.linspace(lo_p, hi_p, 121)
        m, p = np.meshgrid(grid_m, grid_p, indexing="ij")
        err = ((krieger_dougherty(phi[None, None, :], m[..., None], p[..., None]) - mu[None, None, :]) ** 2).sum(-1)
        i, j = np.unravel_index(np.argmin(err), err.shape)
        best = (grid_m[i], grid_p[j])
        dm, dpp = (hi_m - lo_m) / 12, (hi_p - lo_p) / 12
        lo_m, hi_m = max(max(phi) + 1e-4, best[0] - dm), min(PHI_M_MAX, best[0] + dm)
        lo_p, hi_p = max(1e-3, best[1] - dpp), best[1] + dpp
    rmse = float(np.sqrt(np.mean((mu - krieger_dougherty(phi, *best)) ** 2)))
    return best[0], best[1], rmse


def clear_fluid_values(rows):
    """mu_eq/mu0 of the clear fluid (phi = 0) per dp, from the given rows."""
    return {float(r["dp_m"]): float(r["mu_eq_over_mu0"]) for r in rows if float(r["phi"]) == 0}


def clear_value(clear, dp):
    """The clear fluid's mu_eq/mu0 at dp, or the mean over the other resolutions where dp has none (it is the
    viscous term's lattice factor, the same at every dp: 0.9845-0.9849 measured)."""
    return clear[dp] if dp in clear else float(np.mean(list(clear.values())))


def read_reference(path):
    """{phi: dilute-theory mu_eq/mu0 relative to the clear channel} from the reference CSV, or {} without one."""
    if not os.path.isfile(path):
        return {}
    case = RunParams(os.path.join(ROOT, "cases", "poiseuille_loaded.ini"))
    band_clear = local_einstein([], 0.0, case.real("domain", "length_m"), case.real("domain", "height_m"))
    return {float(r["phi"]): float(r["mu_local_einstein"]) / band_clear
            for r in study.read_rows(TOOL, path, dict(phi=float, mu_local_einstein=float))}


def same_model(row, args):
    """Whether a row with the lubrication model ran it with the cut-off, resolved share and tangential film asked
    for."""
    return float(row["lubrication_cutoff_dp"] or 1) == args.cutoff_dp and \
        (row["lubrication_resolved"] or "cutoff") == args.resolved and \
        (row["lubrication_tangential"] or "sliding") == args.tangential


def command_report(args):
    # the clear fluid (phi = 0) has no gaps for the lubrication model: its runs count with the model or without
    every_run = [r for r in study.read_rows(TOOL, args.csv, dict(
        status=str, phi=float, phi_actual=float, dp_m=float, mu_eq_over_mu0=float, wall_s=float if args.png else str,
        c0_mps=float if args.c0 or args.png else str,
        density_diffusion=float if args.diffusion is not None or args.png else str, scheme=str, lubrication=str,
        seed=int, pack_fluid=str, lubrication_cutoff_dp=str, lubrication_resolved=str, lubrication_tangential=str))
        if r["status"] == "ok" and r["scheme"] == args.scheme and int(r["seed"]) == args.seed and
        (float(r["phi"]) == 0 or (r["lubrication"] == str(int(args.lubrication)) and
                                   (r["pack_fluid"] == "1") == args.pack_fluid and
                                   (not args.lubrication or same_model(r, args))))]
    rows = every_run
    if args.diffusion is not None:
        rows = [r for r in rows if float(r["density_diffusion"]) == args.diffusion]
    if args.dp:
        rows = [r for r in rows if abs(float(r["dp_m"]) / args.dp - 1) < 1e-3]
    if args.c0:
        rows = [r for r in rows if abs(float(r["c0_mps"]) / args.c0 - 1) < 1e-3]
    loaded = [r for r in rows if float(r["phi"]) > 0]
    if len(loaded) < 3:
        fail("%s: %d finished runs with discs; the fit needs 3" % (args.csv, len(loaded)))
    clear_all, clear_here = clear_fluid_values(every_run), clear_fluid_values(rows)
    if not clear_all:
        fail("%s: no finished clear-fluid run (phi = 0): mu_eq/mu0 relative to the clear fluid needs one" % args.csv)
    phi = np.array([float(r["phi_actual"]) for r in loaded])
    mu = np.array([float(r["mu_eq_over_mu0"]) for r in loaded])
    phi_m, p, rmse = fit(phi, mu)
    print("Krieger-Dougherty fit of mu_eq/mu0 over %d runs: phi_m = %.4f, p = %.3f, RMSE = %.4f (%.2f %%)%s"
          % (len(loaded), phi_m, p, rmse, 100 * rmse,
             "  [phi_m at its bound %g: the measured viscosity does not diverge]" % PHI_M_MAX
             if phi_m > PHI_M_MAX - 1e-3 else ""))
    for r in rows:
        print("  phi %.4f  mu_eq/mu0 %.4f  wall %s s" % (float(r["phi_actual"]) if r["phi_actual"] != "nan" else 0,
                                                      float(r["mu_eq_over_mu0"]), r["wall_s"]))
    dps = sorted({float(r["dp_m"]) for r in loaded})
    clear = np.array([clear_value(clear_here or clear_all, float(r["dp_m"])) for r in loaded])
    relative = mu / clear
    rel_fit = fit(phi, relative)
    print("Relative to the clear fluid (mu_eq/mu0 = %s at dp %s%s; the viscous term's lattice factor):\n"
          "  fit: phi_m = %.4f, p = %.3f, RMSE = %.4f (%.2f %%)"
          % (", ".join("%.5f" % clear_value(clear_here or clear_all, dp) for dp in dps), ", ".join("%g" % d for d in dps),
             "" if all(dp in clear_here for dp in dps) else ", from the other resolutions' runs", *rel_fit,
             100 * rel_fit[2]))
    reference = read_reference(args.reference)
    for r, f, m in zip(loaded, phi, relative):
        ref = reference.get(float(r["phi"]))
        print("  phi %.4f  rise %.4f  per unit phi %.3f (Einstein-Brady 2D: 2)%s"
              % (f, m - 1, (m - 1) / f, "  dilute theory for these discs %.4f: share %.2f" % (ref - 1, (m - 1) / (ref - 1))
                 if ref else ""))
    if args.png:
        plot(args.png, every_run, reference, rel_fit, same_setting(args))
    return 0


def same_setting(args):
    """Predicate: a row run with the c0 and delta that report selected (every row where neither is given)."""
    def match(r):
        return ((args.c0 is None or abs(float(r["c0_mps"]) / args.c0 - 1) < 1e-3) and
                (args.diffusion is None or float(r["density_diffusion"]) == args.diffusion))
    return match


def plot(png, rows, reference, rel_fit, selected):
    """Left: mu_eq/mu0 relative to the clear fluid against phi, one line per resolution for the runs with the
    selected c0 and delta (other settings in grey), the Krieger-Dougherty fit, Einstein-Brady and the dilute theory
    for the placed discs. Right: accuracy against cost, one point per run of the selected setting: the clear
    fluid's |mu_eq/mu0 - 1|; for dilute loads |1 - rise / the dilute theory's|; for every load at a
    coarser resolution its relative difference from the run at the finest resolution and the same phi."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax, cost) = plt.subplots(1, 2, figsize=(13, 7.5))
    clear = clear_fluid_values(rows)

    def relative_mu(r):
        return float(r["mu_eq_over_mu0"]) / clear_value(clear, float(r["dp_m"]))

    def phi_of(r):
        return float(r["phi_actual"]) if float(r["phi"]) > 0 else 0.0

    others = [r for r in rows if not selected(r)]
    if others:
        ax.plot([phi_of(r) for r in others], [relative_mu(r) for r in others], ".", color="0.75",
                label="surge, other c0 and $\delta$ (poiseuille_loaded.md)")
    mine = [r for r in rows if selected(r)]
    dps = sorted({float(r["dp_m"]) for r in mine}, reverse=True)
    finest = {float(r["phi"]): r for r in mine if float(r["dp_m"]) == dps[-1]}
    for k, dp in enumerate(dps):
        colour = "C%d" % k
        sel = sorted((r for r in mine if float(r["dp_m"]) == dp), key=phi_of)
        name = "r/dp %.0f" % (RADIUS_M / dp)
        setting = "c0 %.3g, $\delta$ %g" % (float(sel[0]["c0_mps"]), float(sel[0]["density_diffusion"]))
        ax.plot([phi_of(r) for r in sel], [relative_mu(r) for r in sel], "o-", lw=0.8, color=colour,
                label="surge, %s, %s" % (name, setting))
        clear_rows = [r for r in sel if float(r["phi"]) == 0]
        if clear_rows:
            cost.loglog([float(r["wall_s"]) for r in clear_rows],
                        [abs(float(r["mu_eq_over_mu0"]) - 1) for r in clear_rows], "s", color=colour, mfc="none",
                        label=name + ", clear fluid: |$\mu_{eq}/\mu_0$ - 1|")
        dilute = [r for r in sel if 0 < float(r["phi"]) <= DILUTE_PHI and float(r["phi"]) in reference]
        if dilute:
            cost.loglog([float(r["wall_s"]) for r in dilute],
                        [abs(1 - (relative_mu(r) - 1) / (reference[float(r["phi"])] - 1)) for r in dilute], "o",
                        color=colour, label=name + ", $\phi \leq$ %g: |1 - rise / dilute theory's|" % DILUTE_PHI)
        coarser = [r for r in sel if float(r["phi"]) > 0 and float(r["phi"]) in finest and dp != dps[-1]]
        if coarser:
            cost.loglog([float(r["wall_s"]) for r in coarser],
                        [abs(relative_mu(r) / relative_mu(finest[float(r["phi"])]) - 1) for r in coarser], "^",
                        color=colour, mfc="none", label=name + ", |1 - $\mu$ / $\mu$ of r/dp %.0f| (same $\phi$)"
                        % (RADIUS_M / dps[-1]))
    top = max(phi_of(r) for r in rows)
    grid = np.linspace(0, top * 1.02, 200)
    ax.plot(grid, krieger_dougherty(grid, rel_fit[0], rel_fit[1]), "-", color="black",
            label="Krieger-Dougherty fit of the selected runs: $\phi_m$ = %.3f, p = %.2f (RMSE %.1f %%)"
            % (rel_fit[0], rel_fit[1], 100 * rel_fit[2]))
    ax.plot(grid[grid <= 0.15], 1 + 2 * grid[grid <= 0.15], "--", color="tab:red", label="Einstein-Brady 2D: 1 + 2$\phi$")
    if reference:
        ax.plot(sorted(reference), [reference[f] for f in sorted(reference)], ":x", color="grey",
                label="dilute theory for the placed discs (local Einstein-Brady)")
    ax.set_xlabel("solid fraction $\phi$")
    ax.set_ylabel("$\mu_{eq}$ / $\mu_{eq}(\phi = 0)$, same dp")
    ax.set_title("Loaded Poiseuille (GMD Sect. 3.2)")
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    ax.grid(alpha=0.3)
    cost.set_xlabel("wall time of the run (s)")
    cost.set_ylabel("error (fraction)")
    cost.set_title("Accuracy against cost")
    cost.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=1)
    cost.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    print("%s: wrote %s" % (TOOL, png))


def command_convergence(args):
    """mu_eq/mu0 per phi and r/dp for one scheme (and c0, delta where given), without and with the lubrication model:
    a table with each value's change from the next coarser resolution, and a chart against r/dp per phi."""
    rows = [r for r in study.read_rows(TOOL, args.csv, dict(
        status=str, phi=float, dp_m=float, mu_eq_over_mu0=float, c0_mps=float, density_diffusion=float, scheme=str,
        lubrication=str, lubrication_cutoff_dp=str, pack_fluid=str, wall_s=float, seed=int, ch=float,
        lubrication_resolved=str, lubrication_tangential=str))
        if r["status"] == "ok" and r["scheme"] == args.scheme and int(r["seed"]) == args.seed and
        abs(float(r["ch"]) - args.ch) < 1e-9 and
        (args.c0 is None or abs(float(r["c0_mps"]) / args.c0 - 1) < 1e-3) and
        (args.diffusion is None or float(r["density_diffusion"]) == args.diffusion) and
        (float(r["phi"]) == 0 or (model_key(r) in args.models and
                                  args.placement in ("both", "packed" if r["pack_fluid"] == "1" else "default")))]
    if not rows:
        fail("%s: no finished %s run with the settings asked" % (args.csv, args.scheme))
    series = {}
    clear = {}
    for r in rows:  # the last row of a (setting, phi, dp) counts: a rerun replaces its run
        cell = (float(r["mu_eq_over_mu0"]), float(r["wall_s"]))
        if float(r["phi"]) == 0:  # the clear fluid has no discs: its runs count for every setting
            clear[round(RADIUS_M / float(r["dp_m"]), 2)] = cell
        else:
            series.setdefault(model_setting(r), {}).setdefault(float(r["phi"]), {})[
                round(RADIUS_M / float(r["dp_m"]), 2)] = cell
    if not series:
        fail("%s: no finished %s run with discs with the settings asked" % (args.csv, args.scheme))
    for setting in series:
        if clear:
            series[setting][0.0] = clear
    for setting in sorted(series):
        by_phi = series[setting]
        resolutions = sorted({rd for values in by_phi.values() for rd in values})
        print("%s scheme, %s: mu_eq/mu0 (change from the next coarser r/dp)" % (args.scheme, setting))
        print("  phi   " + "".join("%20s" % ("r/dp %g" % rd) for rd in resolutions))
        for phi in sorted(by_phi):
            cells, before = [], None
            for rd in resolutions:
                value = by_phi[phi].get(rd)
                if value is None:
                    cells.append("%20s" % "-")
                    continue
                change = "" if before is None else " (%+.1f %%)" % (100 * (value[0] / before - 1))
                cells.append("%20s" % ("%.4f%s" % (value[0], change)))
                before = value[0]
            print("  %-5g " % phi + "".join(cells))
    if args.png:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.lines import Line2D
        fig, ax = plt.subplots(figsize=(9, 9))
        phis = sorted({phi for by_phi in series.values() for phi in by_phi if phi > 0})
        styles = (("o", "-"), ("s", "--"), ("^", ":"), ("D", "-."), ("v", "-"), ("x", "--"))  # marker, line
        for k, phi in enumerate(phis):
            for j, setting in enumerate(sorted(series)):
                values = series[setting].get(phi)
                if not values:
                    continue
                rds = sorted(values)
                marker, line = styles[j % len(styles)]
                ax.plot(rds, [values[rd][0] for rd in rds], marker=marker, linestyle=line, color="C%d" % (k % 10),
                        mfc="none" if j else None)
        ax.set_xlabel("disc radius over particle spacing, r/dp")
        ax.set_ylabel("$\mu_{eq}/\mu_0$")
        ax.set_title("Loaded Poiseuille, %s scheme: convergence in dp" % args.scheme)
        # colour names the solid fraction, the line's style the setting: two legends instead of one per line
        by_phi = ax.legend([Line2D([], [], color="C%d" % (k % 10), lw=2) for k in range(len(phis))],
                           ["$\\phi$ %g" % phi for phi in phis], fontsize=8, loc="center right", title="colour")
        ax.add_artist(by_phi)
        ax.legend([Line2D([], [], color="black", marker=styles[j % len(styles)][0],
                          linestyle=styles[j % len(styles)][1], mfc="none" if j else None)
                   for j in range(len(series))], sorted(series), fontsize=7, loc="upper center",
                  bbox_to_anchor=(0.5, -0.08), title="style")
        ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(args.png, dpi=120)
        print("%s: wrote %s" % (TOOL, args.png))
    return 0


MODELS = ("none", "cutoff", "measured", "reynolds")


def model_key(row):
    """The lubrication model of a table row in one word: none, cutoff (the cut-off share), measured (the measured
    squeeze film with the sliding film) or reynolds (the measured squeeze film with the tangential film)."""
    if row["lubrication"] != "1":
        return "none"
    if row["lubrication_resolved"] != "measured":
        return "cutoff"
    return "reynolds" if row["lubrication_tangential"] == "reynolds" else "measured"


def model_setting(row):
    """The lubrication model and the fluid's placement of a table row, in words."""
    if row["lubrication"] != "1":
        model = "no lubrication model"
    elif row["lubrication_resolved"] == "measured":
        model = "lubrication model, measured share" + \
            (", tangential film from Reynolds" if row.get("lubrication_tangential") == "reynolds" else "")
    else:
        model = "lubrication model, cut-off %s dp" % (row["lubrication_cutoff_dp"] or "1")
    return model + (", fluid packed around the discs" if row["pack_fluid"] == "1" else ", default placement")


def command_seeds(args):
    """mu_eq/mu0 of one scheme per phi and r/dp over the seeds (placements) run: each seed's value, the mean, the
    standard deviation over the seeds, and the change of the mean from the next coarser r/dp with two seeds or more."""
    lubrication = "1" if args.lubrication else "0"
    rows = [r for r in study.read_rows(TOOL, args.csv, dict(
        status=str, phi=float, dp_m=float, mu_eq_over_mu0=float, c0_mps=float, density_diffusion=float, scheme=str,
        lubrication=str, seed=int, pack_fluid=str, lubrication_cutoff_dp=str, lubrication_resolved=str,
        lubrication_tangential=str))
        if r["status"] == "ok" and r["scheme"] == args.scheme and r["lubrication"] == lubrication and
        (r["pack_fluid"] == "1") == args.pack_fluid and (not args.lubrication or same_model(r, args)) and
        (args.c0 is None or abs(float(r["c0_mps"]) / args.c0 - 1) < 1e-3) and
        (args.diffusion is None or float(r["density_diffusion"]) == args.diffusion)]
    if not rows:
        fail("%s: no finished %s run with the settings asked" % (args.csv, args.scheme))
    cells = {}
    for r in rows:  # the last row of a (phi, r/dp, seed) counts: a rerun replaces its run
        cells.setdefault((float(r["phi"]), round(RADIUS_M / float(r["dp_m"]), 2)), {})[int(r["seed"])] = \
            float(r["mu_eq_over_mu0"])
    print("%s scheme, %s: mu_eq/mu0 over the seeds (placements) run"
          % (args.scheme, model_setting({"lubrication": lubrication, "lubrication_resolved": args.resolved,
                                         "lubrication_tangential": args.tangential,
                                         "lubrication_cutoff_dp": "%g" % args.cutoff_dp,
                                         "pack_fluid": "1" if args.pack_fluid else "0"})))
    print("  %-6s %-6s %-6s %-8s %-8s %-28s %s" % ("phi", "r/dp", "seeds", "mean", "sd (%)", "change of the mean",
                                                  "by seed"))
    for phi in sorted({phi for phi, _ in cells}):
        before = None
        for rd in sorted(rd for p, rd in cells if p == phi):
            values = cells[(phi, rd)]
            v = np.array([values[k] for k in sorted(values)])
            mean = v.mean()
            sd = v.std(ddof=1) if v.size > 1 else float("nan")
            change = "-"
            if v.size > 1 and before is not None:
                error = np.hypot(sd / np.sqrt(v.size), before[1] / np.sqrt(before[2])) / before[0]
                change = "%+.1f %% +- %.1f %%" % (100 * (mean / before[0] - 1), 100 * error)
            print("  %-6g %-6g %-6d %-8.4f %-8s %-28s %s" % (
                phi, rd, v.size, mean, "-" if v.size < 2 else "%.1f" % (100 * sd / mean), change,
                " ".join("%d:%.4f" % (k, values[k]) for k in sorted(values))))
            if v.size > 1:
                before = (mean, sd, v.size)
    return 0


def model_list(text):
    """An argparse type: a comma-separated list of lubrication models (MODELS)."""
    names = [t.strip() for t in text.split(",") if t.strip()]
    wrong = [n for n in names if n not in MODELS]
    if not names or wrong:
        raise argparse.ArgumentTypeError("%r: expected a comma-separated list of %s" % (text, ", ".join(MODELS)))
    return tuple(names)


def solid_fractions(with_zero):
    """An argparse type: comma-separated solid fractions in [0, 0.8) (with_zero) or (0, 0.8)."""
    def parse(text):
        try:
            phis = [float(v) for v in text.split(",") if v.strip()]
        except ValueError:
            phis = []
        if not phis or any(not (0 <= v if with_zero else 0 < v) or not v < 0.8 for v in phis):
            raise argparse.ArgumentTypeError("expected comma-separated solid fractions in %s0, 0.8), got '%s'"
                                             % ("[" if with_zero else "(", text))
        return phis
    return parse


def command_layers(args):
    """Prints each run's band velocities and local viscosities side by side, then where its centre speed is gained:
    from the plates to two radii of the largest disc, and from there to the centre."""
    runs = []
    for folder in args.run_dir:
        try:
            runs.append(velocity_layers(folder, args.band_m))
        except (OSError, ValueError) as e:
            fail(str(e))
    if any(r[0].size != runs[0][0].size for r in runs):
        fail("the runs' channels differ in height: their bands do not line up")
    edges = runs[0][0]
    print("distance from the plates (mm) | per run: u (m/s), then mu_local/mu0 to the next band")
    for k in range(edges.size - 1):
        cells = []
        for _, u, mu, _ in runs:
            cells.append("%.6f %8s" % (u[k], "%.3f" % mu[k] if k < mu.size else ""))
        print("%5.1f-%5.1f  %s" % (edges[k] * 1e3, edges[k + 1] * 1e3, "   ".join(cells)))
    for folder, (edges, u, _, radius) in zip(args.run_dir, runs):
        centres = 0.5 * (edges[1:] + edges[:-1])
        if radius > 0 and 2 * radius < centres[-1]:
            at = float(np.interp(2 * radius, centres, u))
            print("%s: %.6f m/s gained from the plates to 2 r (%.0f mm, %.0f %%), %.6f m/s from there to the centre"
                  % (folder, at, 2e3 * radius, 100 * at / u[-1], u[-1] - at))
        else:
            print("%s: no disc, or two radii reach the centre: %.6f m/s at the centre" % (folder, u[-1]))
    return 0


def add_run_selection(parser, default_scheme):
    """The options of `report` and `seeds` that pick the CSV's runs by scheme, films, placement, c0 and delta."""
    parser.add_argument("--scheme", choices=("explicit", "implicit"), default=default_scheme,
                        help="the runs of this scheme (default %s)" % default_scheme)
    parser.add_argument("--lubrication", action="store_true", help="the runs with the lubrication model")
    parser.add_argument("--cutoff-dp", type=cli_checks.positive, default=1.0,
                        help="with --lubrication: the runs with this cut-off (default 1 dp)")
    parser.add_argument("--resolved", choices=("cutoff", "measured"), default="cutoff",
                        help="with --lubrication: the runs with this contacts.lubrication_resolved (default cutoff)")
    parser.add_argument("--tangential", choices=("sliding", "reynolds"), default="sliding",
                        help="with --lubrication: the runs with this contacts.lubrication_tangential (default sliding)")
    parser.add_argument("--pack-fluid", action="store_true", help="the runs with the fluid packed around the discs")
    parser.add_argument("--c0", type=cli_checks.positive, default=None, help="only the runs with this c0")
    parser.add_argument("--diffusion", type=cli_checks.number, default=None, help="only the runs with this delta")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run")
    run.add_argument("--phi", default="0,0.05,0.1,0.2,0.3,0.4,0.5", type=solid_fractions(with_zero=True))
    run.add_argument("--dp", type=cli_checks.positive, default=1 / 150)
    run.add_argument("--ch", type=cli_checks.positive, default=1.8)
    run.add_argument("--seed", type=int, default=1)
    run.add_argument("--c0", type=cli_checks.non_negative, default=0.0,
                     help="numerics.c0_mps (0: the case file's, 15 m/s)")
    run.add_argument("--diffusion", type=cli_checks.number, default=-1.0,
                     help="numerics.density_diffusion (delta; default: the case's)")
    run.add_argument("--threads", type=cli_checks.positive_int, default=2)
    run.add_argument("--scheme", choices=("explicit", "implicit"), default="explicit", help="numerics.scheme")
    run.add_argument("--lubrication", action="store_true",
                     help="contacts.lubrication = true (without it false, though the model is on by default)")
    run.add_argument("--cutoff-dp", type=cli_checks.positive, default=1.0,
                     help="contacts.lubrication_cutoff_dp, the lubrication model's cut-off gap in dp (default 1)")
    run.add_argument("--resolved", choices=("cutoff", "measured"), default="cutoff",
                     help="contacts.lubrication_resolved, what the SPH is taken to resolve of a squeeze film")
    run.add_argument("--tangential", choices=("sliding", "reynolds"), default="sliding",
                     help="contacts.lubrication_tangential, the film's resistance to tangential motion (reynolds "
                     "needs --resolved measured)")
    run.add_argument("--pack-fluid", action="store_true", help="boulders.pack_fluid = true")
    run.add_argument("--budget-s", type=cli_checks.non_negative, default=0.0)
    run.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "poiseuille_loaded"))
    run.add_argument("--csv", default=RUNS_CSV)
    run.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    add = sub.add_parser("add")
    add.add_argument("run_dir", type=cli_checks.folder)
    add.add_argument("--wall-s", type=cli_checks.non_negative, default=float("nan"),
                     help="the run's wall time in seconds, where known (default nan)")
    add.add_argument("--threads", type=cli_checks.positive_int, default=1, help="the threads it ran on (default 1)")
    add.add_argument("--csv", default=RUNS_CSV)
    meas = sub.add_parser("measure")
    meas.add_argument("run_dir")
    sub.add_parser("discs").add_argument("run_dir")
    sub.add_parser("shells").add_argument("run_dir")
    layers = sub.add_parser("layers")
    layers.add_argument("run_dir", nargs="+")
    layers.add_argument("--band-m", type=cli_checks.positive, default=LAYER_BAND_M,
                        help="the bands' width in m (default %g)" % LAYER_BAND_M)
    ref = sub.add_parser("reference")
    ref.add_argument("--phi", default="0.05,0.1,0.2,0.3,0.4,0.5", type=solid_fractions(with_zero=False))
    ref.add_argument("--seed", type=int, default=1)
    ref.add_argument("--runs-dir", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "poiseuille_loaded"))
    ref.add_argument("--csv", default=REFERENCE_CSV)
    ref.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    rep = sub.add_parser("report")
    rep.add_argument("--csv", default=RUNS_CSV)
    rep.add_argument("--png", type=cli_checks.png_file, default=None)
    rep.add_argument("--dp", type=cli_checks.positive, default=None, help="fit only the runs at this dp")
    add_run_selection(rep, default_scheme="explicit")
    rep.add_argument("--reference", default=REFERENCE_CSV)
    rep.add_argument("--seed", type=int, default=1,
                     help="the placement (boulders.seed) of the runs fitted; the reference is seed 1's")
    conv = sub.add_parser("convergence")
    conv.add_argument("--csv", default=RUNS_CSV)
    conv.add_argument("--png", type=cli_checks.png_file, default=None)
    conv.add_argument("--scheme", choices=("explicit", "implicit"), default="implicit", help="the runs of this scheme")
    conv.add_argument("--c0", type=cli_checks.positive, default=None, help="only the runs with this c0")
    conv.add_argument("--diffusion", type=cli_checks.number, default=None, help="only the runs with this delta")
    conv.add_argument("--seed", type=int, default=1, help="the placement (boulders.seed) taken at every resolution")
    conv.add_argument("--ch", type=cli_checks.positive, default=1.8, help="only the runs with this C_h (default 1.8)")
    conv.add_argument("--models", type=model_list, default=MODELS,
                      help="comma-separated lubrication models of the runs taken, of none (the model off), cutoff, "
                      "measured (the measured squeeze film, sliding film) and reynolds (the measured squeeze film, "
                      "tangential film from Reynolds); default all")
    conv.add_argument("--placement", choices=("both", "packed", "default"), default="both",
                      help="the runs with the fluid packed around the discs, at the default placement, or both")
    seeds = sub.add_parser("seeds")
    seeds.add_argument("--csv", default=RUNS_CSV)
    add_run_selection(seeds, default_scheme="implicit")
    args = parser.parse_args()
    if args.command == "convergence":
        return command_convergence(args)
    if args.command == "seeds":
        return command_seeds(args)
    if args.command == "run":
        if not (args.diffusion == -1 or 0 <= args.diffusion <= 1):
            fail("--diffusion must be in [0, 1]")
        if args.tangential == "reynolds" and not (args.lubrication and args.resolved == "measured"):
            fail("--tangential reynolds needs --lubrication and --resolved measured "
                 "(contacts.lubrication_tangential = reynolds leaves out the share of the film the scheme resolves)")
        return command_run(args)
    if args.command == "add":
        return command_add(args)
    if args.command == "reference":
        return command_reference(args)
    if args.command == "measure":
        try:
            u_max, mu_ratio, phi_actual, n = measure(args.run_dir)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("u_max = %.6g m/s, mu_eq/mu0 = %.5g, phi = %.4f (%d discs)" % (u_max, mu_ratio, phi_actual, n))
        return 0
    if args.command == "discs":
        try:
            samples, lag, spread, spin = disc_motion(args.run_dir)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("%d disc samples: (U - u(y)) / u_centre mean %+.4f, sd %.4f; omega / (-u'(y)/2) median %.3f"
              % (samples, lag, spread, spin))
        return 0
    if args.command == "shells":
        try:
            edges, density = shell_density(args.run_dir)
        except (OSError, ValueError) as e:
            fail(str(e))
        print("distance from the disc's face (dp), fluid number density / the lattice's")
        for lo, hi, n in zip(edges[:-1], edges[1:], density):
            print("%.1f-%.1f %.3f" % (lo, hi, n))
        return 0
    if args.command == "layers":
        return command_layers(args)
    return command_report(args)


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
