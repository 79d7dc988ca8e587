#!/usr/bin/python3
"""Validation metrics of a steady viscous front held on a conveyor belt (GMD paper Sect. 3.1,
eqs. 15-18; docs/validation/freydier_metrics.md describes the method, docs/references.md sections 2, 5 and 6
the physics).

Usage:
    tools/freydier_metrics.py RUN_DIR [--window-s 5] [--end-s T] [--png out.png] [--csv-row]

RUN_DIR is a folder written by `surge run` (params.ini, run.pvd, snap_*.vtp). The metrics are
computed over the snapshots in [t_end - window, t_end], t_end = the last snapshot time unless
--end-s is given. A readable summary goes to stdout; --csv-row prints instead one line
    zeta_f,zeta_h,zeta_fs,zeta_u_076,zeta_u_150,zeta_u_970
(fractions, not percent); --png writes a figure of the height and velocity profiles against the
lubrication reference. Bad input gives a one-line error on stderr and exit status 2.

As a module: compute(run_dir, window_s=5.0, end_s=None) -> dict (see its docstring),
h_ref_star(xstar, tan_theta) and u_ref_star(zeta) for the references, read_params(run_dir).
"""

import argparse
import math
import os
import sys

import numpy as np

from surgepy import cli_checks, vtp
from surgepy.run_params import ParamsError, RunParams

PROG = "freydier_metrics"
TOE_FRACTION = 0.1          # toe: where h drops below this fraction of h_n
UNIFORM_XSTAR = 9.0         # uniform zone: x* > 9 ...
WALL_EXCLUSION_HN = 3.0     # ... excluding the 3 h_n next to the upstream wall
FREE_SURFACE_XSTAR = 10.0   # zeta_fs over x* in (0, 10]
STATIONS = (0.76, 1.5, 9.7)  # zeta_u stations, x* upstream of the toe
CSV_HEADER = "zeta_f,zeta_h,zeta_fs,zeta_u_076,zeta_u_150,zeta_u_970"


class MetricsError(Exception):
    """Bad input or a run the metrics cannot be computed on; the message is one line."""


# ------------------------------------------------------------------------------------------------
# References (docs/references.md section 2)
# ------------------------------------------------------------------------------------------------

def h_ref_star(xstar, tan_theta):
    """Lubrication front h/h_n at x* = xi/h_n upstream of the tip: the root eta in [0, 1) of
    artanh(eta) - eta = x* tan(theta); 0 for x* <= 0. Vectorised bisection (64 halvings)."""
    s = np.asarray(xstar, dtype=float) * tan_theta
    lo = np.zeros_like(s)
    hi = np.ones_like(s)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        below = (np.arctanh(np.minimum(mid, 1.0 - 1e-16)) - mid) < s
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    return np.where(s > 0, 0.5 * (lo + hi), 0.0)


def u_ref_star(zeta):
    """Belt-frame velocity normalised by u_b, u* = 3 zeta - 1.5 zeta^2, zeta = z / h_ref."""
    zeta = np.asarray(zeta, dtype=float)
    return 3.0 * zeta - 1.5 * zeta * zeta


# ------------------------------------------------------------------------------------------------
# Inputs
# ------------------------------------------------------------------------------------------------

_REQUIRED = (
    ("fluid", "density_kgpm3"), ("fluid", "viscosity_m2ps"),
    ("walls", "bottom_speed_mps"), ("walls", "upstream_x_m"),
    ("body", "gravity_mps2"), ("body", "slope_deg"),
    ("numerics", "dp_m"), ("domain", "length_m"),
)


def read_params(run_dir):
    """Reads RUN_DIR/params.ini; returns a dict of the values the metrics use and derived ones
    (u_b, h_n, tan_theta, particle_mass). Raises MetricsError on a missing or bad value."""
    try:
        params = RunParams(run_dir)
        p = {"%s.%s" % sk: params.real(*sk) for sk in _REQUIRED}
        p["domain.periodic_x"] = params.flag("domain", "periodic_x", default=False)
        p["walls.layers"] = params.real("walls", "layers", default=0.0)
        upstream = params.flag("walls", "upstream")
    except ParamsError as e:
        raise MetricsError(str(e))
    path = params.path
    if not upstream:
        raise MetricsError("%s: walls.upstream = false: the metrics need the upstream wall that holds the front"
                           % path)

    for key in ("fluid.density_kgpm3", "fluid.viscosity_m2ps", "body.gravity_mps2", "numerics.dp_m",
                "domain.length_m"):
        if p[key] <= 0:
            raise MetricsError("%s: %s = %g must be > 0" % (path, key, p[key]))
    if p["walls.bottom_speed_mps"] == 0:
        raise MetricsError("%s: walls.bottom_speed_mps = 0: no belt, so no held front and no u_b to "
                           "normalise by" % path)
    if p["walls.bottom_speed_mps"] > 0:
        raise MetricsError("%s: walls.bottom_speed_mps = %g > 0: the belt must move upstream (negative "
                           "speed) to hold a front" % (path, p["walls.bottom_speed_mps"]))
    if not 0 < p["body.slope_deg"] < 90:
        raise MetricsError("%s: body.slope_deg = %g must be in (0, 90)" % (path, p["body.slope_deg"]))

    theta = math.radians(p["body.slope_deg"])
    p["u_b"] = abs(p["walls.bottom_speed_mps"])
    p["tan_theta"] = math.tan(theta)
    p["g_sin_theta"] = p["body.gravity_mps2"] * math.sin(theta)
    p["h_n"] = math.sqrt(3.0 * p["fluid.viscosity_m2ps"] * p["u_b"] / p["g_sin_theta"])
    p["particle_mass"] = p["fluid.density_kgpm3"] * p["numerics.dp_m"] ** 2
    return p


def read_entries(run_dir):
    """[(time, absolute path)] of RUN_DIR/run.pvd, sorted by time."""
    path = os.path.join(run_dir, "run.pvd")
    if not os.path.isfile(path):
        raise MetricsError("%s: no run.pvd" % run_dir)
    try:
        entries = vtp.read_pvd(path)
    except vtp.VtpError as e:
        raise MetricsError(str(e))
    if not entries:
        raise MetricsError("%s lists no snapshots" % path)
    out, seen = [], set()
    for t, f in entries:
        entry = (t, os.path.join(run_dir, f))
        if entry not in seen:  # a run may list its last snapshot twice
            seen.add(entry)
            out.append(entry)
    out.sort(key=lambda e: e[0])
    return out


def read_fluid(path, p):
    """Fluid particles of one snapshot: x (unwrapped past the upstream wall when periodic), y,
    vx, volume = m / rho."""
    try:
        d = vtp.read_vtp(path, ("velocity_mps", "density_kgpm3", "kind"))
    except vtp.VtpError as e:
        raise MetricsError(str(e))
    fluid = d["kind"] == 0
    x = d["points"][fluid, 0].astype(float)
    y = d["points"][fluid, 1].astype(float)
    vx = d["velocity_mps"][fluid, 0].astype(float)
    rho = d["density_kgpm3"][fluid].astype(float)
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and np.all(np.isfinite(vx))
            and np.all(np.isfinite(rho)) and np.all(rho > 0)):
        raise MetricsError("snapshot %s: non-finite values or non-positive density in fluid particles" % path)
    if p["domain.periodic_x"]:
        # Fluid that crossed the periodic boundary sits upstream of the wall's particles: move it
        # one period downstream. Fluid inside the wall band (leaked through it) stays where it is.
        wall_back = p["walls.upstream_x_m"] - max(p["walls.layers"], 1.0) * p["numerics.dp_m"]
        x = np.where(x < wall_back, x + p["domain.length_m"], x)
    return x, y, vx, p["particle_mass"] / rho


# ------------------------------------------------------------------------------------------------
# Per-snapshot measures
# ------------------------------------------------------------------------------------------------

def column_heights(x, y, vol, x_wall, dp, nbins):
    """Free-surface elevation per x bin [x_wall + k dp, x_wall + (k+1) dp): by volume (sum of
    particle volumes / dp) and by the top particle + dp/2 (0 for an empty bin)."""
    k = np.floor((x - x_wall) / dp).astype(np.int64)
    inside = (k >= 0) & (k < nbins)
    k = k[inside]
    h_vol = np.bincount(k, weights=vol[inside], minlength=nbins) / dp
    top = np.full(nbins, -np.inf)
    np.maximum.at(top, k, y[inside])
    h_top = np.where(np.isfinite(top), top + 0.5 * dp, 0.0)
    return h_vol, h_top


def find_toe(h, x_centres, threshold, dp):
    """Toe: scanning downstream from the wall, the last bin of the contiguous body with
    h > threshold, refined by linear interpolation of the threshold crossing towards the next
    bin. Returns the x position, or raises MetricsError."""
    above = h > threshold
    first = np.flatnonzero(above)
    if first.size == 0:
        raise MetricsError("no fluid column higher than %.2g h_n" % TOE_FRACTION)
    k0 = first[0]
    gaps = np.flatnonzero(~above[k0:])
    if gaps.size == 0:
        raise MetricsError("the fluid body reaches the end of the domain: no toe")
    k = k0 + gaps[0] - 1
    frac = (h[k] - threshold) / (h[k] - h[k + 1])
    return x_centres[k] + frac * dp


# ------------------------------------------------------------------------------------------------
# Metrics
# ------------------------------------------------------------------------------------------------

def select_window(entries, window_s, end_s):
    if not (window_s > 0 and math.isfinite(window_s)):
        raise MetricsError("--window-s must be a positive number of seconds (got %g)" % window_s)
    first_t, last_t = entries[0][0], entries[-1][0]
    t_end = last_t if end_s is None else float(end_s)
    if not math.isfinite(t_end):
        raise MetricsError("--end-s must be finite")
    eps = 1e-9 * max(1.0, abs(t_end))
    if end_s is not None and not (first_t - eps <= t_end <= last_t + eps):
        raise MetricsError("--end-s %g is outside the run's snapshots [%g, %g] s" % (t_end, first_t, last_t))
    t0 = t_end - window_s
    chosen = [e for e in entries if t0 - eps <= e[0] <= t_end + eps]
    if len(chosen) < 2:
        raise MetricsError("empty window: [%g, %g] s holds %d snapshot(s) of the run's [%g, %g] s; "
                           "need at least 2" % (t0, t_end, len(chosen), first_t, last_t))
    return t0, t_end, chosen


def toe_speed(times, toes, t0, t_end):
    """Least-squares slope of toe position vs time over consecutive ~1 s sub-windows of
    [t0, t_end]; returns (mean slope, [(a, b, slope, n)])."""
    times = np.asarray(times)
    toes = np.asarray(toes)
    window = t_end - t0
    spacing = float(np.median(np.diff(times)))
    if spacing > 0.505:  # a snapshot is written at the first step at or after its time: allow that overshoot
        raise MetricsError("snapshots every %.3g s in the window: zeta_f needs at least 2 per second "
                           "(output snapshot_interval_s <= 0.5)" % spacing)
    n_sub = max(1, int(math.floor(window + 1e-9)))
    length = window / n_sub
    eps = 1e-9 * max(1.0, abs(t_end))
    subs = []
    for i in range(n_sub):
        a, b = t0 + i * length, t0 + (i + 1) * length
        sel = (times >= a - eps) & (times <= b + eps)
        if np.count_nonzero(sel) < 2:
            raise MetricsError("sub-window [%g, %g] s holds %d snapshot(s): zeta_f needs at least 2 "
                               "per second" % (a, b, np.count_nonzero(sel)))
        tt, xx = times[sel], toes[sel]
        slope = float(np.sum((tt - tt.mean()) * (xx - xx.mean())) / np.sum((tt - tt.mean()) ** 2))
        subs.append((a, b, slope, int(np.count_nonzero(sel))))
    return float(np.mean([s[2] for s in subs])), subs


def compute(run_dir, window_s=5.0, end_s=None):
    """Computes the metrics of the run in run_dir over [t_end - window_s, t_end]. Returns a dict:
    zeta_f, zeta_h, zeta_fs, zeta_u {station x*: value}, the top-particle variants zeta_h_top and
    zeta_fs_top, h_n, u_b, t0, t_end, times, toes, toe_subwindows, volume_start/volume_end (fluid
    volume over the run's first snapshot's), profile (grid x*, mean h* by volume and by top
    particle, reference), stations (per-bin data), uniform_zone (x* bounds), params.
    Raises MetricsError on bad input."""
    if not os.path.isdir(run_dir):
        raise MetricsError("%s: no such run folder" % run_dir)
    p = read_params(run_dir)
    entries = read_entries(run_dir)
    t0, t_end, chosen = select_window(entries, window_s, end_s)

    dp, h_n, u_b = p["numerics.dp_m"], p["h_n"], p["u_b"]
    tan_theta = p["tan_theta"]
    x_wall = p["walls.upstream_x_m"]
    x_end = x_wall + p["domain.length_m"] if p["domain.periodic_x"] else p["domain.length_m"]
    nbins = int(math.ceil((x_end - x_wall) / dp - 1e-9))
    if nbins < 2:
        raise MetricsError("domain ends at x = %g m, downstream of the upstream wall at %g m by less than 2 dp"
                           % (x_end, x_wall))
    x_centres = x_wall + (np.arange(nbins) + 0.5) * dp
    threshold = TOE_FRACTION * h_n

    # Velocity stations: z bins of ~dp from 0 to h_ref at the station.
    stations = {}
    for xs in STATIONS:
        h_s = float(h_ref_star(xs, tan_theta)) * h_n
        nz = max(1, int(round(h_s / dp)))
        stations[xs] = {"h_ref": h_s, "edges": np.linspace(0.0, h_s, nz + 1), "sum_sim": np.zeros(nz),
                        "sum_ref": np.zeros(nz), "sum_z": np.zeros(nz), "count": np.zeros(nz)}

    volume0 = float(np.sum(read_fluid(entries[0][1], p)[3]))
    if volume0 <= 0:
        raise MetricsError("the run's first snapshot %s holds no fluid" % entries[0][1])

    times, toes, volumes, per_snap = [], [], [], []
    for t, path in chosen:
        x, y, vx, vol = read_fluid(path, p)
        h_vol, h_top = column_heights(x, y, vol, x_wall, dp, nbins)
        try:
            toe = find_toe(h_vol, x_centres, threshold, dp)
        except MetricsError as e:
            raise MetricsError("snapshot %s (t = %g s): %s" % (path, t, e))
        times.append(t)
        toes.append(toe)
        volumes.append(float(np.sum(vol)))
        per_snap.append(((toe - x_centres) / h_n, h_vol / h_n, h_top / h_n))
        u_star = (vx - p["walls.bottom_speed_mps"]) / u_b  # belt frame, normalised
        for xs, st in stations.items():
            near = np.abs(x - (toe - xs * h_n)) <= dp
            z = y[near]
            b = np.searchsorted(st["edges"], z, side="right") - 1
            b[z == st["h_ref"]] = len(st["count"]) - 1
            ok = (b >= 0) & (b < len(st["count"]))
            b, z = b[ok], z[ok]
            st["sum_sim"] += np.bincount(b, weights=u_star[near][ok], minlength=len(st["count"]))
            st["sum_ref"] += np.bincount(b, weights=u_ref_star(z / st["h_ref"]), minlength=len(st["count"]))
            st["sum_z"] += np.bincount(b, weights=z, minlength=len(st["count"]))
            st["count"] += np.bincount(b, minlength=len(st["count"]))

    toe_mean_speed, subs = toe_speed(times, toes, t0, t_end)
    zeta_f = abs(toe_mean_speed) / u_b

    # Profiles aligned on each snapshot's own toe, on a common x* grid of step dp/h_n.
    step = dp / h_n
    wall_xstar = min((toe - x_wall) / h_n for toe in toes)
    xs_max = wall_xstar - 0.5 * step  # the first bin's centre: no extrapolation
    grid = step * np.arange(int(math.ceil(-2.0 / step)), int(math.floor(xs_max / step)) + 1)
    h_mean = np.zeros_like(grid)
    top_mean = np.zeros_like(grid)
    for xstar_c, hv, ht in per_snap:
        h_mean += np.interp(grid, xstar_c[::-1], hv[::-1])
        top_mean += np.interp(grid, xstar_c[::-1], ht[::-1])
    h_mean /= len(per_snap)
    top_mean /= len(per_snap)
    h_ref = h_ref_star(grid, tan_theta)

    zone_hi = wall_xstar - WALL_EXCLUSION_HN
    zone = (grid > UNIFORM_XSTAR) & (grid < zone_hi)
    if not np.any(zone):
        raise MetricsError("uniform zone x* in (%g, %.3g) is empty: the toe is only %.3g h_n from the upstream "
                           "wall (domain too short; need > %g h_n)"
                           % (UNIFORM_XSTAR, zone_hi, wall_xstar, UNIFORM_XSTAR + WALL_EXCLUSION_HN))
    zeta_h = abs(float(np.mean(h_mean[zone])) - 1.0)
    zeta_h_top = abs(float(np.mean(top_mean[zone])) - 1.0)
    fs = (grid > 0) & (grid <= FREE_SURFACE_XSTAR + 1e-9)
    zeta_fs = float(np.sqrt(np.mean((h_mean[fs] - h_ref[fs]) ** 2)))
    zeta_fs_top = float(np.sqrt(np.mean((top_mean[fs] - h_ref[fs]) ** 2)))

    zeta_u = {}
    for xs, st in stations.items():
        filled = st["count"] > 0
        if not np.any(filled):
            raise MetricsError("no fluid particles within +-dp of the station x* = %g in the window" % xs)
        n = st["count"][filled]
        st["u_sim"] = st["sum_sim"][filled] / n
        st["u_ref"] = st["sum_ref"][filled] / n
        st["z_over_h"] = st["sum_z"][filled] / n / st["h_ref"]
        st["bins_filled"] = int(np.count_nonzero(filled))
        st["bins"] = len(st["count"])
        st["particles"] = int(np.sum(n))
        zeta_u[xs] = float(np.sqrt(np.mean((st["u_sim"] - st["u_ref"]) ** 2)))

    return {
        "run_dir": run_dir, "params": p, "h_n": h_n, "u_b": u_b, "t0": t0, "t_end": t_end,
        "times": times, "toes": toes, "toe_speed": toe_mean_speed, "toe_subwindows": subs,
        "zeta_f": zeta_f, "zeta_h": zeta_h, "zeta_h_top": zeta_h_top, "zeta_fs": zeta_fs,
        "zeta_fs_top": zeta_fs_top, "zeta_u": zeta_u,
        "volume0": volume0, "volume_start": volumes[0] / volume0, "volume_end": volumes[-1] / volume0,
        "profile": {"xstar": grid, "h_vol": h_mean, "h_top": top_mean, "h_ref": h_ref},
        "uniform_zone": (UNIFORM_XSTAR, float(zone_hi)), "wall_xstar": float(wall_xstar),
        "stations": stations,
    }


# ------------------------------------------------------------------------------------------------
# Output
# ------------------------------------------------------------------------------------------------

def csv_row(r):
    values = [r["zeta_f"], r["zeta_h"], r["zeta_fs"]] + [r["zeta_u"][xs] for xs in STATIONS]
    return ",".join("%.6g" % v for v in values)


def summary(r):
    p = r["params"]
    times, toes = np.asarray(r["times"]), np.asarray(r["toes"])
    out = []
    out.append("Freydier front metrics: %s" % r["run_dir"])
    out.append("  reference   h_n = %.4f mm  (nu = %.4g m2/s, u_b = %.4g mm/s, g sin(theta) = %.4g m/s2), "
               "dp = %.3g mm = h_n/%.1f"
               % (1e3 * r["h_n"], p["fluid.viscosity_m2ps"], 1e3 * r["u_b"], p["g_sin_theta"],
                  1e3 * p["numerics.dp_m"], r["h_n"] / p["numerics.dp_m"]))
    out.append("  window      [%.4g, %.4g] s: %d snapshots (median spacing %.3g s)"
               % (r["t0"], r["t_end"], len(times), float(np.median(np.diff(times)))))
    out.append("  fluid volume / first snapshot's (%.6g m2): %.5f at window start, %.5f at window end"
               % (r["volume0"], r["volume_start"], r["volume_end"]))
    out.append("  toe (h = %.2g h_n crossing): x = %.5f .. %.5f m, %.2f h_n from the upstream wall"
               % (TOE_FRACTION, toes.min(), toes.max(), (toes.mean() - p["walls.upstream_x_m"]) / r["h_n"]))
    out.append("  toe speed per sub-window (mm/s): "
               + ", ".join("[%.3g,%.3g] %+.3f" % (a, b, 1e3 * s) for a, b, s, _ in r["toe_subwindows"])
               + "; mean %+.4f mm/s" % (1e3 * r["toe_speed"]))
    out.append("  metrics (fractions; paper's converged values: zeta_f < 0.01, zeta_h < 0.05, "
               "zeta_fs < 0.10, zeta_u < 0.05)")
    out.append("    zeta_f  (eq. 15) |u_f|/u_b                  = %.5f" % r["zeta_f"])
    out.append("    zeta_h  (eq. 16) |<h*> - 1|, x* in (%g, %.3g) = %.5f   (top particle + dp/2: %.5f)"
               % (r["uniform_zone"][0], r["uniform_zone"][1], r["zeta_h"], r["zeta_h_top"]))
    out.append("    zeta_fs (eq. 17) RMS(h* - h*_ref), x* in (0, %g] = %.5f   (top particle + dp/2: %.5f)"
               % (FREE_SURFACE_XSTAR, r["zeta_fs"], r["zeta_fs_top"]))
    for xs in STATIONS:
        st = r["stations"][xs]
        out.append("    zeta_u  (eq. 18) x* = %-4g RMS(u* - u*_ref)   = %.5f   (h_ref = %.3f h_n, %d/%d z bins "
                   "filled, %d particle samples)"
                   % (xs, r["zeta_u"][xs], st["h_ref"] / r["h_n"], st["bins_filled"], st["bins"], st["particles"]))
    out.append("  toe positions x_toe (m) by time (s):")
    pairs = ["%7.3f %.5f" % (t, x) for t, x in zip(times, toes)]
    for i in range(0, len(pairs), 5):
        out.append("    " + "   ".join(pairs[i:i + 5]))
    return "\n".join(out)


def plot(r, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    prof = r["profile"]
    fig = plt.figure(figsize=(12, 8), constrained_layout=True)
    grid = fig.add_gridspec(2, 3)
    ax = fig.add_subplot(grid[0, :])
    ax.plot(prof["xstar"], prof["h_ref"], "k-", lw=1.5, label="lubrication reference")
    ax.plot(prof["xstar"], prof["h_vol"], "C0-", lw=1.2, label="SPH, fluid volume per length / h_n (used)")
    ax.plot(prof["xstar"], prof["h_top"], "C1--", lw=1.0, label="SPH, top particle + dp/2")
    ax.axvspan(r["uniform_zone"][0], r["uniform_zone"][1], color="0.9", label="uniform zone (zeta_h)")
    for xs in STATIONS:
        ax.axvline(xs, color="C2", lw=0.8, ls=":")
    ax.axhline(TOE_FRACTION, color="0.5", lw=0.6, ls=":")
    ax.set_xlim(prof["xstar"][0], prof["xstar"][-1])
    ax.set_xlabel("x* = (x_toe - x) / h_n   (distance upstream of the toe)")
    ax.set_ylabel("h* = h / h_n")
    ax.set_title("(a) free surface, mean over [%.3g, %.3g] s: zeta_h = %.4f, zeta_fs = %.4f   (h_n = %.2f mm; "
                 "stations dotted)" % (r["t0"], r["t_end"], r["zeta_h"], r["zeta_fs"], 1e3 * r["h_n"]))
    ax.legend(loc="lower right", fontsize=8)
    zz = np.linspace(0.0, 1.0, 101)
    for i, xs in enumerate(STATIONS):
        st = r["stations"][xs]
        axu = fig.add_subplot(grid[1, i])
        axu.plot(u_ref_star(zz), zz, "k-", label="reference 3 zeta - 1.5 zeta^2")
        axu.plot(st["u_sim"], st["z_over_h"], "C0o", ms=3, label="SPH (bin means)")
        axu.set_xlabel("u* = (v_x + u_b) / u_b   (belt frame)")
        axu.set_ylabel("z / h_ref(x*)")
        axu.set_title("(b) x* = %g: zeta_u = %.4f" % (xs, r["zeta_u"][xs]))
        axu.set_xlim(left=min(0.0, float(np.min(st["u_sim"])) - 0.05))
        axu.grid(alpha=0.3)
        if i == 0:
            axu.legend(loc="upper left", fontsize=8)
    fig.suptitle("Steady front on a belt: %s" % r["run_dir"], fontsize=10)
    try:
        fig.savefig(png, dpi=110)
    except (OSError, ValueError) as e:
        raise MetricsError("cannot write %s: %s" % (png, str(e).splitlines()[0]))
    finally:
        plt.close(fig)


class _Parser(argparse.ArgumentParser):
    def error(self, message):
        sys.stderr.write("%s: error: %s\n" % (PROG, message))
        sys.exit(2)


def main(argv=None):
    parser = _Parser(prog="freydier_metrics.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("run_dir", metavar="RUN_DIR", help="folder written by `surge run`")
    parser.add_argument("--window-s", type=float, default=5.0, help="averaging window in s (default 5)")
    parser.add_argument("--end-s", type=float, default=None, help="window end in s (default: last snapshot)")
    parser.add_argument("--png", type=cli_checks.png_file, help="write the profile figure to this PNG file")
    parser.add_argument("--csv-row", action="store_true",
                        help="print only '%s' (fractions)" % CSV_HEADER)
    args = parser.parse_args(argv)
    try:
        with np.errstate(all="ignore"):
            r = compute(args.run_dir, args.window_s, args.end_s)
        if args.png:
            plot(r, args.png)
    except MetricsError as e:
        sys.stderr.write("%s: error: %s\n" % (PROG, e))
        return 2
    except Exception as e:  # noqa: BLE001 - never a traceback for a bad run folder
        sys.stderr.write("%s: error: %s: %s\n" % (PROG, type(e).__name__, str(e).splitlines()[0] if str(e) else ""))
        return 2
    print(csv_row(r) if args.csv_row else summary(r))
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
