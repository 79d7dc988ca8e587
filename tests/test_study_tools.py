#!/usr/bin/python3
"""The study drivers' shared pieces and charts: append_row writes the header once, a table with other columns is
refused before a study starts, the standard error of a window mean counts the rows' autocorrelation, bad numeric
options exit 2 with the option named, both charts render from the committed tables, wall_contact measures a synthetic run, and
park / unpark carry an interrupted run through a fresh checkout.
usage: test_study_tools.py SOURCE_DIR WORK_DIR"""
import csv
import os
import random
import shutil
import subprocess
import sys

source, work = sys.argv[1], sys.argv[2]
FC = os.path.join(source, "studies", "freydier", "freydier_convergence.py")
SM = os.path.join(source, "studies", "stability", "stability_map.py")
PL = os.path.join(source, "studies", "poiseuille_loaded", "poiseuille_loaded.py")
from checks import check, finish, load_module  # noqa: E402
from surgepy import study, vtp  # noqa: E402

os.makedirs(work, exist_ok=True)



table = os.path.join(work, "table.csv")
if os.path.exists(table):
    os.remove(table)
study.append_row(table, ["a", "b"], {"a": 1, "b": 2})
study.append_row(table, ["a", "b"], {"a": 3, "b": 4})
with open(table) as f:
    rows = list(csv.reader(f))
check("append_row_header_once", rows == [["a", "b"], ["1", "2"], ["3", "4"]], str(rows))
check("positive_numbers", study.positive_numbers("t", "1,1.3, 2.2", "ch") == [1.0, 1.3, 2.2])

# the standard error of a window mean: white noise gives sd/sqrt(n) and tau 1; an AR(1) series with coefficient 0.5
# (the flow rows' lag-1 autocorrelation is 0.6-0.7) has tau (1 + 0.5)/(1 - 0.5) = 3 and sd sqrt(3/n); a constant
# series has no error; fewer than 4 values, no estimate
rng = random.Random(7)
white = [rng.gauss(0.0, 1.0) for _ in range(4000)]
mean, error, tau = study.mean_with_error(white)
check("mean_with_error: white noise, the error sd/sqrt(n) within 10 %% (%.4f against %.4f), tau %.2f near 1"
      % (error, 1 / 4000 ** 0.5, tau), abs(error * 4000 ** 0.5 - 1) < 0.1 and tau < 1.3)
value, ar1 = rng.gauss(0.0, 1.0) / 0.75 ** 0.5, []
for _ in range(8000):
    value = 0.5 * value + rng.gauss(0.0, 1.0)
    ar1.append(value)
mean, error, tau = study.mean_with_error(ar1)
expected = (3.0 / 0.75 / 8000) ** 0.5  # sd of the series 1/sqrt(1 - 0.25), tau 3
check("mean_with_error: AR(1) at 0.5, tau %.2f within 15 %% of 3 and the error %.4f within 15 %% of %.4f"
      % (tau, error, expected), abs(tau / 3 - 1) < 0.15 and abs(error / expected - 1) < 0.15)
check("mean_with_error: a constant series has no error; three values have no estimate",
      study.mean_with_error([2.0] * 10) == (2.0, 0.0, 1.0) and
      all(v != v for v in study.mean_with_error([1.0, 2.0, 3.0])[1:]))

# a study refuses, before it runs anything, a table whose columns are not its own (an older header)
old_table = os.path.join(work, "old_header.csv")
with open(old_table, "w") as f:
    f.write("case,dp_m,ch\nid1,0.001,1.0\n")
r = subprocess.run([sys.executable, FC, "run", "--csv", old_table, "--surge", sys.executable], capture_output=True,
                   text=True, timeout=60)
check("freydier_convergence refuses a table with other columns", r.returncode == 2 and "columns" in r.stderr
      and old_table in r.stderr, r.stderr.strip())

tools = os.path.join(source, "tools")
for driver, option in ((FC, "--ch"), (SM, "--cfl")):
    tool = os.path.basename(driver)
    for bad in ("0.2,abc", "-1", ""):
        r = subprocess.run([sys.executable, driver, "run", option, bad], capture_output=True, text=True, timeout=60)
        check("%s %s '%s' refused" % (tool, option, bad), r.returncode == 2 and option[2:] in r.stderr,
              r.stderr.strip())
    png = os.path.join(work, tool.replace(".py", ".png"))
    r = subprocess.run([sys.executable, driver, "chart", "--png", png], capture_output=True, text=True, timeout=120)
    check("%s chart" % tool, r.returncode == 0 and os.path.getsize(png) > 10000, r.stderr.strip())

# the loaded-Poiseuille fit recovers the parameters of exact Krieger-Dougherty data, and says when rows are missing
import numpy as np  # noqa: E402
poiseuille_loaded = load_module(PL)
phi = np.array([0.05, 0.1, 0.2, 0.3, 0.4, 0.5])
phi_m, p, rmse = poiseuille_loaded.fit(phi, poiseuille_loaded.krieger_dougherty(phi, 0.62, 2.5))
check("poiseuille_loaded fit recovers phi_m = 0.62, p = 2.5", abs(phi_m - 0.62) < 2e-3 and abs(p - 2.5) < 2e-2
      and rmse < 1e-3, "phi_m %.4f p %.3f rmse %.2g" % (phi_m, p, rmse))
noisy = poiseuille_loaded.krieger_dougherty(phi, 0.62, 2.5) * (1 + 0.05 * np.array([1, -1, 1, -1, 1, -1]))
check("poiseuille_loaded fit RMSE of 5 % noise is about 5 % of the values",
      0.02 < poiseuille_loaded.fit(phi, noisy)[2] < 0.3, str(poiseuille_loaded.fit(phi, noisy)))
# the dilute-theory reference: a clear channel gives the centre band's mean of the parabola, and discs spread
# evenly over the whole gap (area fraction 0.1 at every height) give Einstein-Brady's 1 + 2 phi
clear_band = poiseuille_loaded.local_einstein([], 0.0, 1.0, 0.6)
check("local Einstein-Brady, clear channel: 1 / (1 - d^2 / (3 (B/2)^2)) for the 1 cm band",
      abs(clear_band - 1 / (1 - 0.01 ** 2 / (3 * 0.3 ** 2))) < 1e-5, "%.7f" % clear_band)
centres = (np.arange(3000) + 0.5) * 0.6 / 3000
centres = centres[(centres > 1e-3) & (centres < 0.6 - 1e-3)]
spread = poiseuille_loaded.local_einstein(centres, 1e-3, centres.size * np.pi * 1e-6 / (0.6 * 0.1), 0.6)
check("local Einstein-Brady, discs spread evenly at phi = 0.1: 1.2 (less the walls' thin depleted layer)",
      abs(spread - 1.2) < 0.005, "%.5f" % spread)
short = os.path.join(work, "short.csv")
if os.path.exists(short):
    os.remove(short)
study.append_row(short, poiseuille_loaded.COLUMNS, {"phi": 0.1, "phi_actual": 0.1, "mu_eq_over_mu0": 1.2, "status": "ok",
                                                    "dp_m": 0.005, "ch": 1.8, "seed": 1})
r = subprocess.run([sys.executable, PL, "report", "--csv", short], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded report with one run refused", r.returncode == 2 and "needs 3" in r.stderr, r.stderr.strip())
report_png = os.path.join(work, "poiseuille_loaded.png")
r = subprocess.run([sys.executable, PL, "report", "--dp", "0.005", "--c0", "15", "--diffusion", "0", "--png",
                    report_png], capture_output=True, text=True, timeout=120)
check("poiseuille_loaded report fits and charts the committed table (r/dp 4)",
      r.returncode == 0 and "Krieger-Dougherty fit" in r.stdout and os.path.getsize(report_png) > 10000,
      (r.stdout + r.stderr).strip()[-300:])
r = subprocess.run([sys.executable, PL, "report", "--dp", "0.005", "--scheme", "implicit", "--c0", "15", "--diffusion",
                    "0"], capture_output=True, text=True, timeout=120)
check("poiseuille_loaded report fits one placement: the implicit r/dp 4 runs of seed 1 (6), not the other seeds' rows",
      r.returncode == 0 and "fit of mu_eq/mu0 over 6 runs" in r.stdout, (r.stdout + r.stderr).strip()[-300:])
r = subprocess.run([sys.executable, PL, "report", "--dp", "0.005", "--scheme", "implicit", "--lubrication", "--pack-fluid",
                    "--c0", "15", "--diffusion", "0"], capture_output=True, text=True, timeout=120)
check("poiseuille_loaded report --lubrication --pack-fluid: the six packed r/dp 4 runs with the model at 1 dp",
      r.returncode == 0 and "fit of mu_eq/mu0 over 6 runs" in r.stdout and "2.4804" in r.stdout,
      (r.stdout + r.stderr).strip()[-300:])
r = subprocess.run([sys.executable, PL, "report", "--dp", "0.005", "--scheme", "implicit", "--lubrication", "--pack-fluid",
                    "--cutoff-dp", "2", "--c0", "15", "--diffusion", "0"], capture_output=True, text=True, timeout=120)
check("poiseuille_loaded report --cutoff-dp 2: the one packed r/dp 4 run at 2 dp, too few to fit",
      r.returncode == 2 and "1 finished runs with discs" in r.stderr, (r.stdout + r.stderr).strip()[-300:])
# convergence on a synthetic table: two resolutions without the model, one with it, and a row of another scheme
conv = os.path.join(work, "convergence.csv")
if os.path.exists(conv):
    os.remove(conv)
for phi, dp, mu, lub, scheme in ((0.3, 0.005, 1.5, 0, "implicit"), (0.3, 0.0025, 1.53, 0, "implicit"),
                                 (0.3, 0.005, 1.6, 1, "implicit"), (0.3, 0.0025, 9.0, 0, "explicit")):
    study.append_row(conv, poiseuille_loaded.COLUMNS, {"phi": phi, "phi_actual": phi, "mu_eq_over_mu0": mu, "status": "ok",
                                                       "dp_m": dp, "ch": 1.8, "seed": 1, "c0_mps": 15, "wall_s": 1,
                                                       "density_diffusion": 0, "scheme": scheme, "lubrication": lub})
conv_png = os.path.join(work, "convergence.png")
r = subprocess.run([sys.executable, PL, "convergence", "--csv", conv, "--png", conv_png], capture_output=True,
                   text=True, timeout=120)
lines = r.stdout.splitlines()
check("poiseuille_loaded convergence: r/dp 4 and 8 without the model (+2.0 %), r/dp 4 with it, no explicit row, "
      "a chart", r.returncode == 0 and any("1.5300 (+2.0 %)" in line for line in lines) and
      any("lubrication model, cut-off 1 dp" in line for line in lines) and "9.0000" not in r.stdout and
      os.path.getsize(conv_png) > 10000, (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "convergence", "--csv", conv, "--c0", "40"], capture_output=True, text=True,
                   timeout=60)
check("poiseuille_loaded convergence: no run with the settings asked is refused",
      r.returncode == 2 and "no finished implicit run" in r.stderr, r.stderr.strip())
missing_csv = os.path.join(work, "no_such_table.csv")
r = subprocess.run([sys.executable, PL, "convergence", "--csv", missing_csv], capture_output=True, text=True,
                   timeout=60)
check("poiseuille_loaded convergence: a missing table is refused, named",
      r.returncode == 2 and missing_csv in r.stderr, r.stderr.strip())
# seeds on a synthetic table: r/dp 4 with seeds 1-3 (1.4, 1.5, 1.6), r/dp 8 with seeds 1-2 (1.65, 1.75), and
# convergence keeping to seed 1 (another seed's later row does not replace it)
seeds_csv = os.path.join(work, "seeds.csv")
if os.path.exists(seeds_csv):
    os.remove(seeds_csv)
for dp, seed, mu in ((0.005, 1, 1.4), (0.005, 2, 1.5), (0.005, 3, 1.6), (0.0025, 1, 1.65), (0.0025, 2, 1.75)):
    study.append_row(seeds_csv, poiseuille_loaded.COLUMNS, {
        "phi": 0.5, "phi_actual": 0.5, "mu_eq_over_mu0": mu, "status": "ok", "dp_m": dp, "ch": 1.8, "seed": seed,
        "c0_mps": 15, "wall_s": 1, "density_diffusion": 0, "scheme": "implicit", "lubrication": 0})
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv], capture_output=True, text=True, timeout=60)
# r/dp 4: mean 1.5, sd 0.1 (6.7 %); r/dp 8: mean 1.7, sd 0.0707; change +13.3 % +- hypot(0.1/sqrt 3, 0.0707/sqrt 2)/1.5
rows = {tuple(line.split()[:2]): line.split() for line in r.stdout.splitlines() if line.startswith("  0.5")}
check("poiseuille_loaded seeds: per r/dp the seeds, mean and sd, and the change of the mean with its error",
      r.returncode == 0 and rows.get(("0.5", "4"), [])[2:5] == ["3", "1.5000", "6.7"] and
      rows.get(("0.5", "8"), [])[2:9] == ["2", "1.7000", "4.2", "+13.3", "%", "+-", "5.1"],
      (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv, "--lubrication"], capture_output=True, text=True,
                   timeout=60)
check("poiseuille_loaded seeds: no run with the model is refused", r.returncode == 2 and "no finished" in r.stderr,
      r.stderr.strip())
# the models apart: packed runs with the measured film (2.0, 2.2), one with the cut-off model at 2 dp (9.9) and one
# with the measured film at the default placement (8.8), all at r/dp 4: only the first two are the model asked for
for seed, mu, cutoff, resolved, packed in ((1, 2.0, 1, "measured", 1), (2, 2.2, 1, "measured", 1),
                                         (3, 9.9, 2, "cutoff", 1), (3, 8.8, 1, "measured", 0)):
    study.append_row(seeds_csv, poiseuille_loaded.COLUMNS, {
        "phi": 0.5, "phi_actual": 0.5, "mu_eq_over_mu0": mu, "status": "ok", "dp_m": 0.005, "ch": 1.8, "seed": seed,
        "c0_mps": 15, "wall_s": 1, "density_diffusion": 0, "scheme": "implicit", "lubrication": 1,
        "lubrication_cutoff_dp": cutoff, "lubrication_resolved": resolved, "pack_fluid": packed})
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv, "--lubrication", "--resolved", "measured",
                    "--pack-fluid"], capture_output=True, text=True, timeout=60)
rows = {tuple(line.split()[:2]): line.split() for line in r.stdout.splitlines() if line.startswith("  0.5")}
check("poiseuille_loaded seeds --lubrication --resolved measured --pack-fluid: the two packed measured runs only "
      "(mean 2.1000), named in the header",
      r.returncode == 0 and rows.get(("0.5", "4"), [])[2:4] == ["2", "2.1000"] and
      "measured share, fluid packed" in r.stdout, (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv, "--lubrication", "--cutoff-dp", "2",
                    "--pack-fluid"], capture_output=True, text=True, timeout=60)
rows = {tuple(line.split()[:2]): line.split() for line in r.stdout.splitlines() if line.startswith("  0.5")}
check("poiseuille_loaded seeds --cutoff-dp 2 --pack-fluid: the one run with that cut-off (9.9000)",
      r.returncode == 0 and rows.get(("0.5", "4"), [])[2:4] == ["1", "9.9000"], (r.stdout + r.stderr).strip()[-600:])
# the tangential film apart: a packed run with the measured squeeze film and the tangential film from Reynolds (7.7)
study.append_row(seeds_csv, poiseuille_loaded.COLUMNS, {
    "phi": 0.5, "phi_actual": 0.5, "mu_eq_over_mu0": 7.7, "status": "ok", "dp_m": 0.005, "ch": 1.8, "seed": 1,
    "c0_mps": 15, "wall_s": 1, "density_diffusion": 0, "scheme": "implicit", "lubrication": 1,
    "lubrication_cutoff_dp": 1, "lubrication_resolved": "measured", "pack_fluid": 1,
    "lubrication_tangential": "reynolds"})
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv, "--lubrication", "--resolved", "measured",
                    "--pack-fluid", "--tangential", "reynolds"], capture_output=True, text=True, timeout=60)
rows = {tuple(line.split()[:2]): line.split() for line in r.stdout.splitlines() if line.startswith("  0.5")}
check("poiseuille_loaded seeds --tangential reynolds: the one run with the tangential film (7.7000), named",
      r.returncode == 0 and rows.get(("0.5", "4"), [])[2:4] == ["1", "7.7000"] and
      "tangential film from Reynolds" in r.stdout, (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "seeds", "--csv", seeds_csv, "--lubrication", "--resolved", "measured",
                    "--pack-fluid"], capture_output=True, text=True, timeout=60)
rows = {tuple(line.split()[:2]): line.split() for line in r.stdout.splitlines() if line.startswith("  0.5")}
check("poiseuille_loaded seeds without --tangential: the sliding film's runs, not the tangential film's (2.1000)",
      r.returncode == 0 and rows.get(("0.5", "4"), [])[2:4] == ["2", "2.1000"], (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "convergence", "--csv", seeds_csv, "--models", "reynolds"],
                   capture_output=True, text=True, timeout=60)
check("poiseuille_loaded convergence --models reynolds: the tangential film's runs alone (7.7000)",
      r.returncode == 0 and "7.7000" in r.stdout and "1.4000" not in r.stdout and "2.0000" not in r.stdout and
      "tangential film from Reynolds" in r.stdout, (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "convergence", "--csv", seeds_csv, "--models", "none,measured",
                    "--placement", "packed"], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded convergence --models none,measured --placement packed: the packed measured-film runs "
      "(seed 1: 2.0000), neither the tangential film's nor the default placement's nor the runs without the model",
      r.returncode == 0 and "2.0000" in r.stdout and "7.7000" not in r.stdout and "8.8000" not in r.stdout and
      "1.4000" not in r.stdout, (r.stdout + r.stderr).strip()[-600:])
for bad in (["--models", "reynolds,gap"], ["--models", ""], ["--placement", "loose"]):
    r = subprocess.run([sys.executable, PL, "convergence", "--csv", seeds_csv] + bad, capture_output=True, text=True,
                       timeout=60)
    check("poiseuille_loaded convergence %s refused, named" % " ".join(bad),
          r.returncode == 2 and bad[0] in r.stderr, r.stderr.strip()[-300:])
r = subprocess.run([sys.executable, PL, "run", "--tangential", "reynolds", "--lubrication"],
                   capture_output=True, text=True, timeout=60)
check("poiseuille_loaded run --tangential reynolds without the measured share refused, naming what it needs",
      r.returncode == 2 and "--resolved measured" in r.stderr, r.stderr.strip())
r = subprocess.run([sys.executable, PL, "convergence", "--csv", seeds_csv], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded convergence takes seed 1 at every r/dp: 1.4000 then 1.6500 (+17.9 %)",
      r.returncode == 0 and "1.4000" in r.stdout and "1.6500 (+17.9 %)" in r.stdout, (r.stdout + r.stderr)[-600:])
# disc_motion on a synthetic run: the fluid on the parabola u = 4 U y (B - y) / B^2, two discs moving at the fluid's
# speed at their heights less 1 % of U, turning at 0.9 of -u'(y)/2
synthetic = os.path.join(work, "pl_discs")
os.makedirs(synthetic, exist_ok=True)
B, U = 0.6, 0.08
ys = np.linspace(0.005, B - 0.005, 60)
fluid_xy = np.stack([np.zeros_like(ys), ys], axis=1)
discs_y = np.array([0.2, 0.45])
fluid_entries, disc_entries = [], []
for k, t in enumerate((0.8, 0.9, 1.0)):
    u = 4 * U * ys * (B - ys) / B ** 2
    vtp.write_vtp(os.path.join(synthetic, "snap_%d.vtp" % k), fluid_xy,
                  {"kind": np.zeros(ys.size, dtype=np.int32), "velocity_mps": np.stack([u, 0 * u], axis=1)}, t, k)
    ud = 4 * U * discs_y * (B - discs_y) / B ** 2 - 0.01 * U
    shear = 4 * U * (B - 2 * discs_y) / B ** 2
    vtp.write_vtp(os.path.join(synthetic, "discs_%d.vtp" % k), np.stack([0 * discs_y, discs_y], axis=1),
                  {"velocity_mps": np.stack([ud, 0 * ud], axis=1), "omega_radps": 0.9 * -shear / 2}, t, k)
    fluid_entries.append((t, "snap_%d.vtp" % k))
    disc_entries.append((t, "discs_%d.vtp" % k))
vtp.write_pvd(os.path.join(synthetic, "run.pvd"), fluid_entries)
vtp.write_pvd(os.path.join(synthetic, "boulders.pvd"), disc_entries)
samples, lag, spread, spin = poiseuille_loaded.disc_motion(synthetic)
check("poiseuille_loaded disc_motion: 6 samples, lag -0.01 of the centre speed, spin 0.9",
      samples == 6 and abs(lag + 0.01) < 1e-5 and spread < 1e-5 and abs(spin - 0.9) < 1e-5,  # stored in float32
      "%d %.6g %.3g %.6g" % (samples, lag, spread, spin))
# shell_density on the synthetic run's folder with one disc clear of the plates (r 0.02 m at (0.5, 0.3) m, dp 1 mm)
# and a fluid laid on circles about it: a shell of three times the lattice's density 0.45 dp from its face, the
# lattice's density 0.05-1.95 dp out elsewhere, and one disc 1 dp from the lower plate, whose annuli are left out
dp_s, r_s = 0.001, 0.02
with open(os.path.join(synthetic, "params.ini"), "w") as f:
    f.write("[domain]\nlength_m = 1\nheight_m = 0.6\n[numerics]\ndp_m = %g\n" % dp_s)
points = []
for k in range(20):
    d = (k + 0.5) * 0.1 * dp_s
    n = round((3 if k == 4 else 1) * np.pi * ((r_s + (k + 1) * 0.1 * dp_s) ** 2 - (r_s + k * 0.1 * dp_s) ** 2) / dp_s ** 2)
    angles = 2 * np.pi * (np.arange(n) + 0.5) / n
    points += [(0.5 + (r_s + d) * np.cos(a), 0.3 + (r_s + d) * np.sin(a)) for a in angles]
points = np.array(points)
shell_expected = np.array([round((3 if k == 4 else 1) * np.pi * ((r_s + (k + 1) * 0.1 * dp_s) ** 2 -
                                                                 (r_s + k * 0.1 * dp_s) ** 2) / dp_s ** 2) /
                           (np.pi * ((r_s + (k + 1) * 0.1 * dp_s) ** 2 - (r_s + k * 0.1 * dp_s) ** 2) / dp_s ** 2)
                           for k in range(20)])
for k, t in enumerate((0.8, 0.9, 1.0)):
    vtp.write_vtp(os.path.join(synthetic, "snap_%d.vtp" % k), points,
                  {"kind": np.zeros(len(points), dtype=np.int32)}, t, k)
    vtp.write_vtp(os.path.join(synthetic, "discs_%d.vtp" % k), np.array([[0.5, 0.3], [0.2, r_s + dp_s]]),
                  {"radius_m": np.array([r_s, r_s])}, t, k)
edges, density = poiseuille_loaded.shell_density(synthetic)
check("poiseuille_loaded shell_density: 3 in the shell 0.4-0.5 dp out, 1 elsewhere (to the counts' rounding)",
      len(density) == 20 and abs(edges[-1] - 2) < 1e-12 and np.allclose(density, shell_expected, atol=1e-6)
      and abs(density[4] - 3) < 0.1 and np.all(np.abs(np.delete(density, 4) - 1) < 0.2),
      " ".join("%.3f" % x for x in density))
# velocity_layers on a synthetic channel: the fluid on the steady parabola u = F y (B - y) / (2 nu0) reads a local
# viscosity of exactly mu0 in every band (a band's mean of a parabola is its centre value less the same amount in
# every band); a disc (r 20 mm at y 0.1 m, no fluid within it) moving at V without turning reads V in its bands
layered = os.path.join(work, "pl_layers")
os.makedirs(layered, exist_ok=True)
F_l, nu_l, V_l = 0.8, 0.467, 0.003
with open(os.path.join(layered, "params.ini"), "w") as f:
    f.write("[domain]\nlength_m = 1\nheight_m = 0.6\n[fluid]\nviscosity_m2ps = %g\n[body]\nforce_x_mps2 = %g\n"
            "[numerics]\ndp_m = 0.001\n" % (nu_l, F_l))
if os.path.exists(os.path.join(layered, "boulders.pvd")):
    os.remove(os.path.join(layered, "boulders.pvd"))


def layered_fluid(ys):
    for k, t in enumerate((0.8, 0.9, 1.0)):
        u = F_l * ys * (B - ys) / (2 * nu_l)
        vtp.write_vtp(os.path.join(layered, "snap_%d.vtp" % k), np.stack([0 * ys, ys], axis=1),
                      {"kind": np.zeros(ys.size, dtype=np.int32), "velocity_mps": np.stack([u, 0 * u], axis=1)}, t, k)


ys = np.arange(0.0005, 0.6, 0.001)
layered_fluid(ys)
vtp.write_pvd(os.path.join(layered, "run.pvd"), [(t, "snap_%d.vtp" % k) for k, t in enumerate((0.8, 0.9, 1.0))])
edges, u_bands, mu_local, radius = poiseuille_loaded.velocity_layers(layered)
check("poiseuille_loaded velocity_layers: a clear parabola reads mu_local/mu0 = 1 in every band (30 bands of 10 mm)",
      edges.size == 31 and radius == 0 and np.all(np.abs(mu_local - 1) < 1e-3),
      " ".join("%.4f" % m for m in mu_local))
layered_fluid(ys[(np.abs(ys - 0.1) > 0.02) & (np.abs(ys - 0.5) > 0.02)])  # the upper half folds onto the lower
for k, t in enumerate((0.8, 0.9, 1.0)):
    vtp.write_vtp(os.path.join(layered, "discs_%d.vtp" % k), np.array([[0.5, 0.1]]),
                  {"velocity_mps": np.array([[V_l, 0.0]]), "omega_radps": np.array([0.0]), "radius_m": np.array([0.02])},
                  t, k)
vtp.write_pvd(os.path.join(layered, "boulders.pvd"), [(t, "discs_%d.vtp" % k) for k, t in enumerate((0.8, 0.9, 1.0))])
edges, u_bands, mu_local, radius = poiseuille_loaded.velocity_layers(layered)
check("poiseuille_loaded velocity_layers: a disc moving at V without turning reads V in the bands it fills (80-120 mm)",
      radius == 0.02 and np.allclose(u_bands[8:12], V_l, rtol=1e-6), " ".join("%.6f" % v for v in u_bands[6:14]))
r = subprocess.run([sys.executable, PL, "layers", layered, layered, "--band-m", "0.02"], capture_output=True, text=True,
                   timeout=60)
check("poiseuille_loaded layers: two runs side by side, each one's speed gained to 2 r (40 mm) and beyond",
      r.returncode == 0 and r.stdout.count("gained from the plates to 2 r (40 mm") == 2 and " 0.0- 20.0" in r.stdout,
      (r.stdout + r.stderr).strip()[-600:])
r = subprocess.run([sys.executable, PL, "layers", layered, "--band-m", "0.4"], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded layers: a band wider than half the channel is refused, named",
      r.returncode == 2 and "fewer than two bands" in r.stderr, (r.stdout + r.stderr).strip()[-300:])

# add: a finished run made by hand, its settings read from its params.ini (the implicit scheme, the model at a 2 dp
# cut-off, the fluid packed), measured into a table: the fluid on the parabola of centre speed U gives
# mu_eq/mu0 = B^2 F / (8 U nu0) = 0.36 * 0.5 / (8 * 0.08 * 0.25) = 1.125 over the band within 1 cm of the centre
added = os.path.join(work, "pl_added")
os.makedirs(added, exist_ok=True)
band = np.linspace(0.291, 0.309, 10)
for k, t in enumerate((0.8, 0.9, 1.0)):
    vtp.write_vtp(os.path.join(added, "snap_%d.vtp" % k), np.stack([0 * band, band], axis=1),
                  {"kind": np.zeros(band.size, dtype=np.int32), "velocity_mps": np.stack([U + 0 * band, 0 * band], axis=1)},
                  t, k)
    vtp.write_vtp(os.path.join(added, "discs_%d.vtp" % k), np.array([[0.5, 0.3]]), {"radius_m": np.array([0.02])}, t, k)
vtp.write_pvd(os.path.join(added, "run.pvd"), [(t, "snap_%d.vtp" % k) for k, t in enumerate((0.8, 0.9, 1.0))])
vtp.write_pvd(os.path.join(added, "boulders.pvd"), [(t, "discs_%d.vtp" % k) for k, t in enumerate((0.8, 0.9, 1.0))])
with open(os.path.join(added, "params.ini"), "w") as f:
    f.write("# derived: h_m = 0.009, c0_mps = 15 (expected speed 0.077 m/s)\n# derived: fluid particles = 1000\n"
            "[domain]\nlength_m = 1\nheight_m = 0.6\n[fluid]\ndensity_kgpm3 = 1000\nviscosity_m2ps = 0.25\n"
            "[body]\nforce_x_mps2 = 0.5\n[numerics]\nscheme = implicit\ndp_m = 0.005\nch = 1.8\n"
            "density_diffusion = 0\n[boulders]\nplacement = random\nsolid_fraction = 0.3\nseed = 2\n"
            "pack_fluid = true\n[contacts]\nlubrication = true\nlubrication_cutoff_dp = 2\n"
            "lubrication_resolved = measured\nlubrication_tangential = reynolds\n[time]\nend_s = 1\n")
with open(os.path.join(added, "diagnostics.csv"), "w") as f:
    f.write("time_s,step\n0,0\n1.0,40\n")
with open(os.path.join(added, "checkpoint.bin"), "wb") as f:
    f.write(b"stand-in")
added_csv = os.path.join(work, "added.csv")
if os.path.exists(added_csv):
    os.remove(added_csv)
r = subprocess.run([sys.executable, PL, "add", added, "--csv", added_csv, "--wall-s", "12.5"], capture_output=True,
                   text=True, timeout=60)
added_rows = study.read_rows("test", added_csv, {}) if os.path.exists(added_csv) else []
expected = {"phi": "0.3", "dp_m": "0.005", "ch": "1.8", "seed": "2", "wall_s": "12.5", "particle_steps": "40000",
            "sim_time_s": "1.000", "mu_eq_over_mu0": "1.125", "n_discs": "1", "status": "ok", "c0_mps": "15",
            "density_diffusion": "0", "scheme": "implicit", "lubrication": "1", "lubrication_cutoff_dp": "2",
            "pack_fluid": "1", "lubrication_resolved": "measured", "lubrication_tangential": "reynolds"}
check("poiseuille_loaded add: one row with the run's settings, measured (mu_eq/mu0 1.125)",
      r.returncode == 0 and len(added_rows) == 1 and all(added_rows[0][k] == v for k, v in expected.items()),
      "%s %s" % (added_rows, r.stderr.strip()))
r = subprocess.run([sys.executable, PL, "convergence", "--csv", added_csv, "--seed", "2"], capture_output=True,
                   text=True, timeout=60)
check("poiseuille_loaded convergence names the run's model and placement",
      r.returncode == 0 and "lubrication model, measured share, tangential film from Reynolds, fluid packed around "
      "the discs" in r.stdout,
      (r.stdout + r.stderr).strip()[-400:])
with open(os.path.join(added, "diagnostics.csv"), "w") as f:
    f.write("time_s,step\n0,0\n0.5,20\n")
r = subprocess.run([sys.executable, PL, "add", added, "--csv", added_csv], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded add: a run stopped at 0.5 s of its 1 s refused, named, and not added",
      r.returncode == 2 and added in r.stderr and "not finished" in r.stderr and len(study.read_rows("test", added_csv, {})) == 1,
      r.stderr.strip())
os.remove(os.path.join(added, "checkpoint.bin"))
r = subprocess.run([sys.executable, PL, "add", added, "--csv", added_csv], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded add: a folder without a checkpoint refused, named", r.returncode == 2 and added in r.stderr,
      r.stderr.strip())
r = subprocess.run([sys.executable, PL, "shells", work], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded shells: a folder that is not a run refused with its name",
      r.returncode == 2 and work in r.stderr, r.stderr.strip())
r = subprocess.run([sys.executable, PL, "discs", work], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded discs: a folder without discs refused with its name", r.returncode == 2 and work in r.stderr,
      r.stderr.strip())
r = subprocess.run([sys.executable, PL, "run", "--phi", "0.9"], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded run --phi 0.9 refused", r.returncode == 2 and "--phi" in r.stderr, r.stderr.strip())
r = subprocess.run([sys.executable, PL, "run", "--diffusion", "2"], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded run --diffusion 2 refused", r.returncode == 2 and "--diffusion" in r.stderr, r.stderr.strip())
r = subprocess.run([sys.executable, PL, "reference", "--phi", "0.9"], capture_output=True, text=True, timeout=60)
check("poiseuille_loaded reference --phi 0.9 refused", r.returncode == 2 and "--phi" in r.stderr, r.stderr.strip())

# wall_contact: a synthetic belt run with one particle 0.4 dp behind the upstream wall's face and a bed layer
# at 0.25 dp over 12-112 mm
from surgepy import vtp  # noqa: E402
contact_dir = os.path.join(work, "wall_contact")
shutil.rmtree(contact_dir, ignore_errors=True)  # a rerun must not see the broken snapshot written below
os.makedirs(contact_dir)
with open(os.path.join(contact_dir, "params.ini"), "w") as f:
    f.write("[walls]\nupstream = true\nupstream_x_m = 0.012\n[numerics]\ndp_m = 0.001\n"
            "[fluid]\ndensity_kgpm3 = 1000\n")
xs = np.arange(0.0125, 0.15, 0.001)
points = [(x, 0.00025, 0) for x in xs] + [(x, 0.005, 0) for x in xs] + [(0.0116, 0.0005, 0)]
rho = np.full(len(points), 1000.0)
rho[-1] = 1030.0
vtp.write_vtp(os.path.join(contact_dir, "snap_000000001.vtp"), points,
              {"kind": np.zeros(len(points)), "density_kgpm3": rho}, 1.0, 1)
r = subprocess.run([sys.executable, os.path.join(tools, "wall_contact.py"), contact_dir], capture_output=True,
                   text=True, timeout=60)
last = r.stdout.strip().splitlines()[-1] if r.stdout.strip() else ""
check("wall_contact: behind_wall 0.40, corner_y 0.25, corner_drho 0.03 from a synthetic run",
      r.returncode == 0 and "behind_wall mean 0.40 max 0.40; corner_y min 0.25; corner_drho mean 0.0300" in last,
      last or r.stderr.strip())
check("wall_contact: bed layer 0.25 dp over 12-112 mm", "12-112:0.25" in r.stdout, r.stdout.strip()[:200])
r = subprocess.run([sys.executable, os.path.join(tools, "wall_contact.py"), work], capture_output=True, text=True,
                   timeout=60)
check("wall_contact without params.ini refused", r.returncode == 2 and "params.ini" in r.stderr, r.stderr.strip())
with open(os.path.join(contact_dir, "snap_000000002.vtp"), "w") as f:
    f.write("not a VTK file")
r = subprocess.run([sys.executable, os.path.join(tools, "wall_contact.py"), contact_dir], capture_output=True,
                   text=True, timeout=60)
check("wall_contact: a broken snapshot is named, no traceback",
      r.returncode == 2 and "snap_000000002.vtp" in r.stderr and "Traceback" not in r.stderr, r.stderr.strip())
# park / unpark: an interrupted run's checkpoint, small files and first snapshot go into the parked folder and come
# back byte for byte; later snapshots, finished runs and a folder that already holds a run are left alone
runs_dir, parked_dir, restored_dir = (os.path.join(work, d) for d in ("park_runs", "parked", "restored_runs"))
for d in (runs_dir, parked_dir, restored_dir):
    shutil.rmtree(d, ignore_errors=True)
import struct  # noqa: E402
header_params = b"[numerics]\ndp_m = 0.001\n"
checkpoint = (b"SURGECK1" + struct.pack("<IIQ", 2, 4, len(header_params)) + header_params
              + struct.pack("<qd", 120, 0.5) + bytes(range(256)) * 40)
files = {"checkpoint.bin": checkpoint, "params.ini": b"# derived: fluid particles = 10, wall particles = 2\n",
         "diagnostics.csv": b"time_s,step\n0,0\n0.5,120\n", "snap_000000000.vtp": b"first snapshot",
         "snap_000000120.vtp": b"later snapshot",
         "run.pvd": b'<?xml version="1.0"?><VTKFile type="Collection"><Collection>'
                    b'<DataSet timestep="0" file="snap_000000000.vtp"/>'
                    b'<DataSet timestep="0.5" file="snap_000000120.vtp"/></Collection></VTKFile>'}
for name, status in (("interrupted_run", "interrupted"), ("finished_run", "ok")):
    os.makedirs(os.path.join(runs_dir, name))
    for f, data in files.items():
        with open(os.path.join(runs_dir, name, f), "wb") as out:
            out.write(data)
    study.write_progress(os.path.join(runs_dir, name), {"wall_s": 12.5, "status": status})
check("checkpoint_time reads step and time from the header",
      study.checkpoint_time(os.path.join(runs_dir, "interrupted_run", "checkpoint.bin")) == (120, 0.5))
check("park takes the interrupted run only", study.park("t", runs_dir, parked_dir) == ["interrupted_run"])
check("park compresses the checkpoint and the first snapshot, not later ones",
      sorted(os.listdir(os.path.join(parked_dir, "interrupted_run"))) ==
      ["checkpoint.bin.gz", "diagnostics.csv", "params.ini", "progress.json", "run.pvd", "snap_000000000.vtp.gz"],
      str(os.listdir(os.path.join(parked_dir, "interrupted_run"))))
os.makedirs(os.path.join(parked_dir, "another_study"))  # another study's parked runs: not a run folder
with open(os.path.join(parked_dir, "README.md"), "w") as out:
    out.write("parked runs\n")
check("unpark restores the parked run, and only it", study.unpark("t", parked_dir, restored_dir) == ["interrupted_run"]
      and sorted(os.listdir(restored_dir)) == ["interrupted_run"])
restored = os.path.join(restored_dir, "interrupted_run")
same = all(open(os.path.join(restored, f), "rb").read() == data for f, data in files.items()
           if f != "snap_000000120.vtp")
check("unpark gives back the files byte for byte", same and not os.path.exists(os.path.join(restored,
                                                                                            "snap_000000120.vtp")))
check("unpark keeps the run's status and wall time", study.read_progress(restored) == {"wall_s": 12.5,
                                                                                      "status": "interrupted"})
with open(os.path.join(restored, "checkpoint.bin"), "wb") as out:
    out.write(b"newer")
check("unpark leaves a folder that already holds a run", study.unpark("t", parked_dir, restored_dir) == []
      and open(os.path.join(restored, "checkpoint.bin"), "rb").read() == b"newer")
# a run still going is parked at its last checkpoint, its current piece counted up to that checkpoint, but not
# before this piece has written one
running = os.path.join(runs_dir, "interrupted_run")
mtime = os.path.getmtime(os.path.join(running, "checkpoint.bin"))
study.write_progress(running, {"wall_s": 12.5, "status": "running", "piece_started_unix": mtime + 5})
check("park skips a running run with no checkpoint of its current piece",
      study.park("t", runs_dir, os.path.join(work, "parked_none")) == [])
study.write_progress(running, {"wall_s": 12.5, "status": "running", "piece_started_unix": mtime - 30})
parked_running = os.path.join(work, "parked_running")
shutil.rmtree(parked_running, ignore_errors=True)
check("park takes a running run at its checkpoint", study.park("t", runs_dir, parked_running) == ["interrupted_run"])
progress = study.read_progress(os.path.join(parked_running, "interrupted_run"))
check("a running run is parked as interrupted with its piece's time up to the checkpoint",
      progress["status"] == "interrupted" and abs(progress["wall_s"] - 42.5) < 1e-6
      and "piece_started_unix" not in progress, str(progress))

# the frozen-lattice analysis of the implicit step (docs/validation/stability.md, "Short steps in a thin fluid"): with
# the kernels cut off under the surface the step grows 1.39 a step without viscosity; with the surface's mirror
# images and the pressure's relaxation (the defaults) it grows less than 1 + 1e-2 at every nu dt / dp^2 (1.0001 at
# 0), and without the relaxation the images' near-null modes grow up to 1.0069
IM = os.path.join(source, "studies", "stability", "implicit_surface_modes.py")
r = subprocess.run([sys.executable, IM], capture_output=True, text=True, timeout=300)
radii = {line[:44].strip(): [float(v) for v in line[44:].split()] for line in r.stdout.splitlines()
         if line.startswith("  ")}
check("implicit_surface_modes: cut-off kernels 1.3934 and 1.2710 at nu dt/dp^2 0 and 0.2; adjoints 1; the default "
      "(images and relaxation) below 1 + 1e-2 at every nu dt/dp^2 and below 1.0002 at 0",
      r.returncode == 0 and abs(radii["cut-off kernels (surface_images 0)"][0] - 1.3934) < 1e-3
      and abs(radii["cut-off kernels (surface_images 0)"][3] - 1.2710) < 1e-3
      and max(radii["d_adjoint: divergence -G^T"] + radii["g_adjoint: gradient -D^T"]) < 1.0001
      and max(radii["images, relaxation 0.5 (the default)"]) < 1.0002
      and 1.005 < radii["images, no relaxation"][0] < 1.01, r.stdout + r.stderr)
r = subprocess.run([sys.executable, IM, "--ch", "9"], capture_output=True, text=True, timeout=60)
check("implicit_surface_modes --ch 9 refused", r.returncode == 2 and "--ch" in r.stderr, r.stderr.strip())
sys.exit(finish())
