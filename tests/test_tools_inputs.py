#!/usr/bin/python3
"""Bad inputs to the Python tools (tools/*.py, tools/surgectl, bench/*.py, the study drivers in studies/*/): each
gets a clear error naming what is wrong, exit status 2 (3 for surgectl's unexpected replies), and never a traceback,
a hang or a number printed from garbage.

usage: test_tools_inputs.py SURGE SOURCE_DIR WORK_DIR

One tiny real run (about 2 s) gives the files; the damaged inputs are built from it in WORK_DIR: snapshots without
points or a kind array or with NaN, malformed run.pvd, bad params.ini, CSV tables with garbage, checkpoints and
parked runs that cannot be restored, stand-in surge scripts (exit at once, or write nothing), and ZeroMQ peers that send garbage.
Each check prints "name: ok" or "name: FAILED ..."; the script exits 1 if any failed.
"""
import csv
import json
import os
import re
import shutil
import subprocess
import sys
import threading
import time

import numpy as np
import zmq

SURGE, SOURCE, WORK = sys.argv[1:4]
TOOLS = os.path.join(SOURCE, "tools")
FC = os.path.join(SOURCE, "studies", "freydier", "freydier_convergence.py")
SM = os.path.join(SOURCE, "studies", "stability", "stability_map.py")
PL = os.path.join(SOURCE, "studies", "poiseuille_loaded", "poiseuille_loaded.py")
SP = os.path.join(SOURCE, "studies", "spreading", "spreading.py")
RB = os.path.join(SOURCE, "bench", "render_bench.py")
AB = os.path.join(SOURCE, "bench", "ab_bench.py")
SC = os.path.join(SOURCE, "bench", "scaling.py")
from checks import check, finish, load_module  # noqa: E402
from surgepy import vtp  # noqa: E402
from surgepy.run_params import RunParams  # noqa: E402
freydier_convergence = load_module(FC)
poiseuille_loaded = load_module(PL)




def tool(name, *args, timeout=60):
    """Runs tools/NAME, or the script at the absolute path NAME, with args; returns the completed process."""
    return subprocess.run([sys.executable, os.path.join(TOOLS, name)] + [str(a) for a in args], capture_output=True,
                          text=True, timeout=timeout, stdin=subprocess.DEVNULL)


def expect(name, r, *words, rc=2):
    """The tool exited with rc, its stderr holds every word and no traceback."""
    check(name, r.returncode == rc and all(w in r.stderr for w in words) and "Traceback" not in r.stderr,
          "rc %d (expected %d), stderr: %s" % (r.returncode, rc, r.stderr.strip()[-600:]))


def path(*parts):
    return os.path.join(WORK, *parts)


def folder(name, files=()):
    """A fresh folder in WORK with copies of the real run's files."""
    d = path(name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    for f in files:
        shutil.copy(path("run", f), d)
    return d


def write(file, data):
    with open(file, "wb" if isinstance(data, bytes) else "w") as f:
        f.write(data)
    return file


def params_with(**values):
    """The real run's params.ini with a `key = value` line in place of its own for each of values."""
    text = PARAMS
    for key, value in values.items():
        text = re.sub(r"(?m)^%s = .*$" % key, "%s = %s" % (key, value), text, count=1)
    return text


def script(name, text):
    """An executable shell script in WORK (a stand-in for surge)."""
    write(path(name), "#!/bin/sh\n" + text)
    os.chmod(path(name), 0o755)
    return path(name)


def serve(endpoint, kind, frames, stop):
    """A ZeroMQ peer until stop is set: PUB sends frames over and over, REP answers each request with frames."""
    sock = zmq.Context.instance().socket(kind)
    sock.bind(endpoint)
    while not stop.is_set():
        if kind == zmq.PUB:
            sock.send_multipart(frames)
            time.sleep(0.05)
        elif sock.poll(50):
            sock.recv()
            sock.send_multipart(frames)
    sock.close(linger=0)


def with_peer(endpoint, kind, frames, run):
    stop = threading.Event()
    peer = threading.Thread(target=serve, args=(endpoint, kind, frames, stop), daemon=True)
    peer.start()
    try:
        return run()
    finally:
        stop.set()
        peer.join(5)


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)

# ---- the real run: 0.2 s of a coarse ID1 front, snapshots every 0.05 s ----
r = subprocess.run([SURGE, "run", os.path.join(SOURCE, "cases", "freydier_id1.ini"), "-o", path("run"),
                    "-s", "numerics.dp_m=0.004", "-s", "time.end_s=0.2", "-s", "walls.upstream_x_m=0.03",
                    "-s", "fluid.x0_m=0.03", "-s", "fluid.x1_m=0.3", "-s", "fluid.shape=lubrication",
                    "-s", "output.snapshot_interval_s=0.05", "-s", "output.progress_interval_s=0", "--threads", "1"],
                   capture_output=True, text=True, timeout=120, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
if r.returncode != 0:
    print("the tiny real run failed:\n" + r.stderr)
    sys.exit(1)
PARAMS = open(path("run", "params.ini")).read()
SNAPS = [f for _, f in vtp.read_pvd(path("run", "run.pvd"))]
FIRST = open(path("run", SNAPS[0]), "rb").read()
RUN_FILES = ["params.ini", "run.pvd", "diagnostics.csv"] + SNAPS


def damaged(name, change):
    """A copy of the run whose first snapshot's bytes are change(bytes)."""
    d = folder(name, RUN_FILES)
    write(os.path.join(d, SNAPS[0]), change(FIRST))
    return d


def rewritten(name, **arrays):
    """A copy of the run whose snapshots are rewritten with some arrays replaced by arrays[name](snapshot)."""
    d = folder(name, RUN_FILES)
    for f in SNAPS:
        s = vtp.read_vtp(path("run", f))
        point_data = {k: s[k] for k in ("velocity_mps", "density_kgpm3", "pressure_pa", "kind", "id")}
        point_data.update({k: change(s) for k, change in arrays.items()})
        vtp.write_vtp(os.path.join(d, f), s["points"], point_data, s["time_s"], s["step"])
    return d


no_points = damaged("no_points", lambda b: b.replace(b"Points>", b"Pointz>", 2))
bad_xml = damaged("bad_xml", lambda b: b.replace(b"<PointData", b"<Point<Data", 1))
no_kind = damaged("no_kind", lambda b: b.replace(b'Name="kind"', b'Name="kinx"', 1))
no_offset = damaged("no_offset", lambda b: b.replace(b'offset="0"', b'offzet="0"', 1))
non_finite = rewritten("non_finite", density_kgpm3=lambda s: np.where(s["kind"] == 0, np.nan, s["density_kgpm3"]))
no_fluid = rewritten("no_fluid", kind=lambda s: np.ones_like(s["kind"]))

# ---- 1. python/surgepy/vtp.py: one error class, naming the file, for every malformed input ----
for name, d in (("no <Points>", no_points), ("malformed XML", bad_xml), ("no offset attribute", no_offset)):
    try:
        vtp.read_vtp(os.path.join(d, SNAPS[0]))
        check("read_vtp: " + name, False, "no error")
    except vtp.VtpError as e:
        check("read_vtp: " + name, SNAPS[0] in str(e) and d in str(e), str(e))
try:
    vtp.read_vtp(os.path.join(no_kind, SNAPS[0]), ("kind",))
    check("read_vtp: a required array missing", False, "no error")
except vtp.VtpError as e:
    check("read_vtp: a required array missing", "no kind array" in str(e), str(e))
bad_pvd = write(path("bad.pvd"), open(path("run", "run.pvd")).read().replace('file="', 'fil="', 1))
try:
    vtp.read_pvd(bad_pvd)
    check("read_pvd: a DataSet without a file", False, "no error")
except vtp.VtpError as e:
    check("read_pvd: a DataSet without a file", bad_pvd in str(e) and "file" in str(e), str(e))

# ---- 2. the study drivers and surge's own errors ----
refusing = script("surge_refusing", 'echo "surge: bad option (stand-in)" >&2\nexit 2\n')
header_only = folder("header_only", ["params.ini"])
write(os.path.join(header_only, "diagnostics.csv"), open(path("run", "diagnostics.csv")).readline())
copying = script("surge_header_only",  # a surge that "runs" by copying header_only into its -o folder
                 'out=""; prev=""\nfor a in "$@"; do [ "$prev" = "-o" ] && out="$a"; prev="$a"; done\n'
                 'mkdir -p "$out" && cp %s/* "$out"/\n' % header_only)
common = ["--cases", "id1", "--dp", "0.004", "--ch", "1.8", "--end-s", "0.2", "--runs-dir", path("fc_runs"),
          "--csv", path("fc.csv"), "--parked-dir", path("fc_parked")]
expect("freydier_convergence run: surge exits 2 at once: its message", tool(FC, "run", "--surge", refusing, *common),
       "surge: bad option (stand-in)", "status 2")
expect("freydier_convergence run: diagnostics.csv with a header only",
       tool(FC, "run", "--surge", copying, *common), "diagnostics.csv", "no rows")
expect("stability_map run: surge exits 2 at once: its message",
       tool(SM, "run", "--surge", refusing, "--shifting", "none", "--ch", "1.8", "--cfl", "0.2", "--c0-factor", "10",
            "--runs-dir", path("sm_runs"), "--csv", path("sm.csv"), "--frames", path("sm_frames")),
       "surge: bad option (stand-in)")
expect("poiseuille_loaded run: surge exits 2 at once: its message",
       tool(PL, "run", "--surge", refusing, "--phi", "0", "--runs-dir", path("pl_runs"), "--csv", path("pl.csv")),
       "surge: bad option (stand-in)")
silent = script("surge_silent", "exit 0\n")  # a surge that "succeeds" and writes nothing
expect("poiseuille_loaded reference: surge wrote no run",
       tool(PL, "reference", "--surge", silent, "--phi", "0.1", "--runs-dir", path("pl_runs"),
            "--csv", path("pl_ref.csv")), "phi = 0.1", "wrote no run")
expect("poiseuille_loaded reference: --csv in a missing folder",
       tool(PL, "reference", "--surge", SURGE, "--phi", "0.1", "--runs-dir", path("pl_runs"),
            "--csv", path("missing", "pl_ref.csv")), "--csv", "missing")
expect("freydier_convergence run --cases id3 refused before anything runs",
       tool(FC, "run", "--surge", refusing, "--cases", "id1,id3"), "--cases", "id3")
expect("freydier_convergence run --end-s nan", tool(FC, "run", "--surge", refusing, "--end-s", "nan"), "--end-s")
expect("freydier_convergence run --dp inf", tool(FC, "run", "--surge", refusing, "--dp", "inf"), "--dp")
expect("freydier_convergence run --surge a folder", tool(FC, "run", "--surge", WORK), "--surge", "not an executable")
expect("stability_map run --end-s -1", tool(SM, "run", "--surge", refusing, "--end-s", "-1"), "--end-s")
expect("stability_map implicit-run --steps-ms -1", tool(SM, "implicit-run", "--surge", refusing, "--steps-ms", "1,-1"),
       "--steps-ms", "-1")
expect("stability_map implicit-run: surge exits 2 at once: its message",
       tool(SM, "implicit-run", "--surge", refusing, "--steps-ms", "2", "--runs-dir", path("sm_runs"),
            "--implicit-csv", path("sm_implicit.csv")), "surge: bad option (stand-in)")
expect("poiseuille_loaded run --c0 -1", tool(PL, "run", "--surge", refusing, "--c0", "-1"), "--c0")

# ---- 3. park and unpark: bad checkpoints, progress files, archives; nothing half-written ----
bad_ck_runs = folder("park_runs")
os.makedirs(os.path.join(bad_ck_runs, "a"))
write(os.path.join(bad_ck_runs, "a", "progress.json"), '{"status": "interrupted", "wall_s": 1.5}')
write(os.path.join(bad_ck_runs, "a", "checkpoint.bin"), b"garbage, not a checkpoint")
parked = folder("parked")
os.makedirs(os.path.join(parked, "a"))
write(os.path.join(parked, "a", "earlier"), "an earlier parked copy")
expect("park: a bad checkpoint", tool(FC, "park", "--runs-dir", bad_ck_runs, "--parked-dir", parked),
       "checkpoint.bin", "not a surge checkpoint")
check("park: the earlier parked copy is left as it was, nothing half-written",
      sorted(os.listdir(parked)) == ["a"] and os.listdir(os.path.join(parked, "a")) == ["earlier"],
      str(os.listdir(parked)))
write(os.path.join(bad_ck_runs, "a", "progress.json"), '["interrupted"]')
expect("park: progress.json not an object with a status",
       tool(FC, "park", "--runs-dir", bad_ck_runs, "--parked-dir", parked), "progress.json")
for name, files in (("corrupt .gz", {"checkpoint.bin.gz": b"\x1f\x8b\x08\x00garbage"}),
                    ("a folder inside the parked run", {"sub/": None})):
    source = folder("unpark_source")
    os.makedirs(os.path.join(source, "b"))
    write(os.path.join(source, "b", "progress.json"), '{"status": "interrupted", "wall_s": 1.5}')
    for f, data in files.items():
        if data is None:
            os.makedirs(os.path.join(source, "b", f))
        else:
            write(os.path.join(source, "b", f), data)
    restored = folder("unpark_runs")
    expect("unpark: " + name, tool(FC, "unpark", "--parked-dir", source, "--runs-dir", restored), "parked run")
    check("unpark: %s leaves nothing in the runs folder" % name, os.listdir(restored) == [], str(os.listdir(restored)))
expect("park --parked-dir a file", tool(FC, "park", "--runs-dir", bad_ck_runs, "--parked-dir",
                                        path("run", "params.ini")), "--parked-dir", "not a folder")
# the debris ensemble's park, unpark and run take the same folder checks
ENSEMBLE = os.path.join(SOURCE, "studies", "debris_surge", "ensemble.py")
for command in ("park", "unpark", "run"):
    expect("ensemble %s --parked-dir a file" % command, tool(ENSEMBLE, command, "--parked-dir",
                                                             path("run", "params.ini")), "--parked-dir", "not a folder")
expect("ensemble lift: not a run folder", tool(ENSEMBLE, "lift", WORK), WORK, "params.ini")
expect("ensemble lift: a run without disc snapshots", tool(ENSEMBLE, "lift", path("run")), "boulders.pvd")
expect("ensemble lift --window 5 3", tool(ENSEMBLE, "lift", path("run"), "--window", "5", "3"), "--window")
expect("ensemble shape: not a run folder", tool(ENSEMBLE, "shape", WORK), WORK, "params.ini")
expect("ensemble shape --window 5 3", tool(ENSEMBLE, "shape", path("run"), "--window", "5", "3"), "--window")
expect("ensemble shape --body 4 2", tool(ENSEMBLE, "shape", path("run"), "--body", "4", "2"), "--body")
expect("ensemble history --window 5 3", tool(ENSEMBLE, "history", path("run"), "--window", "5", "3"), "--window")
expect("ensemble history: not a folder", tool(ENSEMBLE, "history", path("run", "params.ini")), "not a folder")
garbage_flow = folder("garbage_flow")
write(os.path.join(garbage_flow, "flow.csv"), "time_s,froude,mu_eq_over_mu0\n0,0,inf\n0.5,abc,2\n")
expect("ensemble history: a flow.csv value that is not a number: file, line and column",
       tool(ENSEMBLE, "history", garbage_flow), "flow.csv", "line 3", "froude")
expect("ensemble history --block-s 1e-6: too many blocks", tool(ENSEMBLE, "history", garbage_flow, "--block-s", "1e-6"),
       "--block-s 1e-06", "more than 100000 blocks")
good_flow = folder("good_flow")
write(os.path.join(good_flow, "flow.csv"), "time_s,froude,mu_eq_over_mu0\n0,0,inf\n1,0.8,2\n2,0.8,2\n3,0.8,2\n")
# a table written into a folder that does not exist, or onto a folder, is refused before any work; one that the
# system refuses while it is written (/dev/full: no space left) is named too
for command, run_args in (("history", [good_flow]), ("shape", [path("run")]), ("collect", ["--runs-dir", WORK])):
    expect("ensemble %s --csv in a missing folder" % command,
           tool(ENSEMBLE, command, *run_args, "--csv", path("no_such_folder", "t.csv")), "--csv", "no_such_folder")
    expect("ensemble %s --csv a folder" % command, tool(ENSEMBLE, command, *run_args, "--csv", WORK), "--csv",
           "is a folder")
expect("ensemble history --csv that cannot be written", tool(ENSEMBLE, "history", good_flow, "--csv", "/dev/full"),
       "--csv /dev/full", "cannot write it")
expect("ensemble shape --csv that cannot be written", tool(ENSEMBLE, "shape", path("run"), "--window", "0", "5",
                                                           "--body", "0", "1", "--csv", "/dev/full"),
       "--csv /dev/full", "cannot write it")
expect("surge_drift --csv that cannot be written", tool("surge_drift.py", path("run"), "--ignore-m", "0", "--csv",
                                                        "/dev/full"), "--csv /dev/full", "cannot write it")
expect("surge_drift --csv in a missing folder", tool("surge_drift.py", path("run"), "--csv",
                                                     path("no_such_folder", "d.csv")), "--csv", "no_such_folder")
expect("ensemble park --runs-dir a file", tool(ENSEMBLE, "park", "--runs-dir", path("run", "params.ini")),
       "--runs-dir", "not a folder")

# ---- 4. CSV tables and --png ----
garbage_csv = path("fc_garbage.csv")
with open(garbage_csv, "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=freydier_convergence.COLUMNS)
    writer.writeheader()
    writer.writerow(dict({c: "1" for c in freydier_convergence.COLUMNS}, case="id1", status="ok", dp_m="abc"))
expect("freydier_convergence chart: a value that is not a number: file, line and column",
       tool(FC, "chart", "--csv", garbage_csv, "--png", path("fc.png")), garbage_csv, "line 2", "dp_m")
expect("freydier_convergence run: the same table refused before anything runs",
       tool(FC, "run", "--surge", refusing, "--csv", garbage_csv), "dp_m")
binary_csv = write(path("binary.csv"), bytes(range(256)) * 8)
expect("stability_map chart: a binary file", tool(SM, "chart", "--csv", binary_csv), binary_csv, "not a CSV")
expect("stability_map chart: --png into a missing folder",
       tool(SM, "chart", "--png", path("nowhere", "map.png")), "--png", "nowhere")
expect("freydier_convergence chart: --png with another extension", tool(FC, "chart", "--png", path("chart.svg")),
       "--png", ".png")
no_clear = path("pl_no_clear.csv")
with open(no_clear, "w", newline="") as f:
    writer = csv.DictWriter(f, fieldnames=poiseuille_loaded.COLUMNS)
    writer.writeheader()
    for phi in (0.1, 0.2, 0.3):
        writer.writerow(dict(dict.fromkeys(poiseuille_loaded.COLUMNS, "1"), phi=phi, phi_actual=phi, status="ok",
                             mu_eq_over_mu0=1 + 2 * phi, scheme="explicit", lubrication=0, pack_fluid=0))
r = tool(PL, "report", "--csv", no_clear)
expect("poiseuille_loaded report without a phi = 0 run", r, "phi = 0")
check("poiseuille_loaded report without a phi = 0 run prints no nan", "nan" not in r.stdout, r.stdout)
expect("poiseuille_loaded report of the implicit runs when the table has none", tool(PL, "report", "--csv", no_clear,
       "--scheme", "implicit"), "0 finished runs")
expect("poiseuille_loaded add: a folder that does not exist", tool(PL, "add", path("no_such_run"), "--csv", no_clear),
       "no_such_run", "checkpoint")
expect("poiseuille_loaded add: --wall-s -1", tool(PL, "add", path("no_such_run"), "--wall-s", "-1"), "--wall-s")
expect("poiseuille_loaded run --cutoff-dp 0", tool(PL, "run", "--cutoff-dp", "0", "--csv", no_clear), "--cutoff-dp")
expect("poiseuille_loaded seeds --cutoff-dp -1", tool(PL, "seeds", "--cutoff-dp", "-1", "--csv", no_clear),
       "--cutoff-dp")
expect("poiseuille_loaded seeds --resolved exact", tool(PL, "seeds", "--resolved", "exact", "--csv", no_clear),
       "--resolved", "exact")
expect("poiseuille_loaded run: a scheme that does not exist", tool(PL, "run", "--scheme", "sph", "--csv", no_clear),
       "--scheme", "sph")

# ---- 5. operator_check ----
OC = "operator_check.py"
box = ["--x", "0.05", "0.2", "--y", "0.002", "0.01"]
r = tool(OC, path("run"), *box, "--every", "2", "--last", "2")
check("operator_check on the real run", r.returncode == 0 and "nu_eff / nu" in r.stdout, r.stderr.strip())
expect("operator_check --every 0", tool(OC, path("run"), *box, "--every", "0"), "--every")
expect("operator_check --last 0", tool(OC, path("run"), *box, "--last", "0"), "--last")
expect("operator_check: a reversed box", tool(OC, path("run"), "--x", "0.2", "0.05", "--y", "0.002", "0.01"), "X0 < X1")
expect("operator_check: a box with no fluid", tool(OC, path("run"), "--x", "5", "6", "--y", "0.002", "0.01"),
       "no fluid particle in the box")
r = tool(OC, non_finite, *box)
expect("operator_check: NaN in a snapshot", r, "non-finite", "density_kgpm3")
check("operator_check: NaN in a snapshot prints no nan", "nan" not in r.stdout, r.stdout)
bad_params = folder("bad_params", RUN_FILES)
write(os.path.join(bad_params, "params.ini"), params_with(dp_m="abc"))
expect("operator_check: a bad params.ini", tool(OC, bad_params, *box), "params.ini", "dp_m")

# ---- 6. drift_map ----
expect("drift_map without arguments", tool("drift_map.py"), "usage")
check("drift_map --help", tool("drift_map.py", "--help").returncode == 0)
expect("drift_map: no kind array", tool("drift_map.py", no_kind, SNAPS[0]), "no kind array")
expect("drift_map: malformed XML", tool("drift_map.py", bad_xml, SNAPS[0]), SNAPS[0], "malformed XML")
expect("drift_map: no fluid", tool("drift_map.py", no_fluid, SNAPS[0]), "no fluid")
no_key = folder("no_key", RUN_FILES)
write(os.path.join(no_key, "params.ini"), PARAMS.replace("upstream_x_m =", "upstream_y_m =", 1))
expect("drift_map: a missing params.ini key", tool("drift_map.py", no_key, SNAPS[0]), "upstream_x_m")

# ---- 7. wall_contact ----
r = tool("wall_contact.py", path("run"), "--after-s", "0.1")
check("wall_contact on the real run", r.returncode == 0 and "after 0.1 s" in r.stdout, r.stderr.strip())
expect("wall_contact: no <Points>", tool("wall_contact.py", no_points), SNAPS[0], "no <Points>")
no_corner = rewritten("no_corner", kind=lambda s: np.where(  # the corner's fluid (3 dp = 12 mm) turned to wall
    (s["kind"] == 0) & (s["points"][:, 0] < 0.042) & (s["points"][:, 1] < 0.012), 1, s["kind"]))
r = tool("wall_contact.py", no_corner, "--after-s", "0.1")
check("wall_contact: no fluid in the corner is said, not printed as nan",
      r.returncode == 0 and "no fluid within 3 dp" in r.stdout and "nan" not in r.stdout.splitlines()[-1]
      and "Warning" not in r.stderr, r.stdout[-300:] + r.stderr)
expect("wall_contact: NaN density", tool("wall_contact.py", non_finite), "non-finite", "density_kgpm3")
expect("wall_contact --after-s nan", tool("wall_contact.py", path("run"), "--after-s", "nan"), "--after-s")
expect("wall_contact: no snapshot after --after-s", tool("wall_contact.py", path("run"), "--after-s", "100"),
       "no snapshot after")

# ---- 8. poiseuille_loaded measure (a run driven along x, its snapshots listed in the window) ----
def driven(name, force, height):
    """A copy of the run with a body force along x, a channel of the given height and its snapshots listed at
    0.8-0.95 s (the window of the measurement)."""
    d = folder(name, RUN_FILES)
    write(os.path.join(d, "params.ini"), params_with(force_x_mps2=force, height_m=height))
    vtp.write_pvd(os.path.join(d, "run.pvd"), [(0.8 + 0.05 * k, f) for k, f in enumerate(SNAPS[:4])])
    return d


expect("poiseuille_loaded measure: force_x_mps2 = 0",
       tool(PL, "measure", driven("force0", 0, 0.02)), "force_x_mps2")
expect("poiseuille_loaded measure: no fluid in the centre band",
       tool(PL, "measure", driven("empty_band", 1, 0.2)), "centre line")
d = driven("measure_no_kind", 1, 0.02)
shutil.copy(os.path.join(no_kind, SNAPS[0]), d)
expect("poiseuille_loaded measure: no kind array", tool(PL, "measure", d), SNAPS[0], "kind")
d = driven("measure_bad_pvd", 1, 0.02)
write(os.path.join(d, "run.pvd"), "<VTKFile")
expect("poiseuille_loaded measure: malformed run.pvd", tool(PL, "measure", d), "run.pvd")

# ---- 8b. disc_on_bed measure ----
DB = os.path.join(SOURCE, "studies", "boulders", "disc_on_bed.py")
expect("disc_on_bed measure: a missing folder", tool(DB, "measure", path("no_such_run")), "no_such_run")
expect("disc_on_bed measure: a run without discs", tool(DB, "measure", folder("no_discs", RUN_FILES)), "boulders.pvd")
d = folder("one_disc_file", RUN_FILES)
vtp.write_pvd(os.path.join(d, "boulders.pvd"), [(0.0, "boulders_000000000.vtp")])
expect("disc_on_bed measure: one disc file", tool(DB, "measure", d), "at least 3")


def disc_files(name, centres, times, radius=0.0125):
    """A copy of the run with boulders.pvd and one disc file per time; centres(t) gives the discs' (x, y)."""
    d = folder(name, RUN_FILES)
    entries = []
    for k, t in enumerate(times):
        f = "boulders_%09d.vtp" % k
        xy = np.array(centres(t), dtype=float)
        vtp.write_vtp(os.path.join(d, f), xy, {"radius_m": np.full(len(xy), radius)}, t, k)
        entries.append((t, f))
    vtp.write_pvd(os.path.join(d, "boulders.pvd"), entries)
    return d


ROW_TIMES = [0.25 * k for k in range(17)]
expect("disc_on_bed row: a missing folder", tool(DB, "row", path("no_such_run")), "no_such_run")
expect("disc_on_bed row: a run without discs", tool(DB, "row", folder("row_no_discs", RUN_FILES)), "boulders.pvd")
expect("disc_on_bed row: one disc a file", tool(DB, "row", disc_files("row_one", lambda t: [(0.01, 0.05)], ROW_TIMES)),
       "two a period")
expect("disc_on_bed row: discs closer than a diameter",
       tool(DB, "row", disc_files("row_close", lambda t: [(0.01, 0.05), (0.03, 0.05)], ROW_TIMES)), "diameter")
# a row falling at 1 mm/s with a gap of a quarter radius: W/U and the slot's resistance from the run's parameters
d = disc_files("row_falling", lambda t: [(0.01, 0.05 - 0.001 * t), (0.038125, 0.05 - 0.001 * t)], ROW_TIMES)
write(os.path.join(d, "params.ini"), params_with(density_ratio=2))
r = tool(DB, "row", d)
rp = RunParams(d)
rho0, nu = rp.positive("fluid", "density_kgpm3"), rp.positive("fluid", "viscosity_m2ps")
weight = (rp.positive("boulders", "density_ratio") - 1) * rho0 * rp.positive("body", "gravity_mps2") * np.pi * 0.0125 ** 2
slot = 4.5 * np.pi * rho0 * nu * 0.028125 ** 2 * np.sqrt(0.0125) / 0.003125 ** 2.5
check("disc_on_bed row: W/U and the slot's resistance of a row falling at 1 mm/s",
      r.returncode == 0 and r.stdout.count("W/U = %.4g " % (weight / 0.001)) == 4 and ("%.4g" % slot) in r.stdout
      and "s/a 0.250" in r.stdout, r.stdout + r.stderr)

# share: a disc falling at 1 mm/s from 20 to 16 mm over the bed, W/U over the exact resistance at each gap it passes
expect("disc_on_bed share: a missing folder", tool(DB, "share", path("no_such_run")), "no_such_run")
expect("disc_on_bed share: a run without discs", tool(DB, "share", folder("share_no_discs", RUN_FILES)), "boulders.pvd")
expect("disc_on_bed share: a disc at rest",
       tool(DB, "share", disc_files("share_still", lambda t: [(0.05, 0.0325)], ROW_TIMES)), "never approaches")
d = disc_files("share_falling", lambda t: [(0.05, 0.0325 - 0.001 * t)], ROW_TIMES)
write(os.path.join(d, "params.ini"), params_with(density_ratio=2))
r = tool(DB, "share", d)
rp = RunParams(d)
mu, h_kernel = rp.positive("fluid", "density_kgpm3") * rp.positive("fluid", "viscosity_m2ps"), rp.derived("h_m")
weight = (2 - 1) * rp.positive("fluid", "density_kgpm3") * rp.positive("body", "gravity_mps2") * np.pi * 0.0125 ** 2
rows = [line.split() for line in r.stdout.splitlines()[2:]]
worst = 0.0
for gap_h, gap_dp, share, t in rows:
    alpha = np.arccosh(1 + float(gap_h) * h_kernel / 0.0125)
    exact = 4 * np.pi * mu / (alpha - np.tanh(alpha))
    worst = max(worst, abs(float(share) / (weight / 0.001 / exact) - 1))
gaps_passed = len([k for k in range(1, 1000) if 0.016 < k * 0.125 * h_kernel < 0.02])  # 4 s at 1 mm/s
check("disc_on_bed share: W/U over the exact resistance at each gap 0.125 h apart that a disc falling at 1 mm/s "
      "passes (%d rows, worst %.2g)" % (len(rows), worst),
      r.returncode == 0 and len(rows) == gaps_passed and worst < 2e-3, r.stdout + r.stderr)
# --onto disc: a disc of radius a falling at 1 mm/s onto a disc of radius 2a at rest, its gap 20 to 16 mm at an angle;
# the exact resistance with the reduced radius 2a/3
expect("disc_on_bed share --onto disc: one disc", tool(DB, "share", d, "--onto", "disc"), "needs 2")
expect("disc_on_bed share --onto: a word it does not know", tool(DB, "share", d, "--onto", "wall"), "invalid choice")
expect("disc_on_bed share --onto disc: two discs at rest",
       tool(DB, "share", disc_files("share_pair_still", lambda t: [(0.05, 0.07), (0.05, 0.0375)], ROW_TIMES),
            "--onto", "disc"), "never approaches the second disc")
reach = 0.0125 + 0.025 + 0.02  # centre to centre at the start


def pair_centres(t):
    along = reach - 0.001 * t
    return [(0.05 + 0.6 * along, 0.0375 + 0.8 * along), (0.05, 0.0375)]


d = disc_files("share_pair", pair_centres, ROW_TIMES)
for k, t in enumerate(ROW_TIMES):  # the second disc twice the first's radius
    f = os.path.join(d, "boulders_%09d.vtp" % k)
    vtp.write_vtp(f, np.array(pair_centres(t)), {"radius_m": np.array([0.0125, 0.025])}, t, k)
write(os.path.join(d, "params.ini"), params_with(density_ratio=2))
r = tool(DB, "share", d, "--onto", "disc")
rows = [line.split() for line in r.stdout.splitlines()[2:]]
worst = 0.0
for gap_h, gap_dp, share, t in rows:
    alpha = np.arccosh(1 + float(gap_h) * h_kernel / (0.0125 * 0.025 / 0.0375))
    exact = 4 * np.pi * mu / (alpha - np.tanh(alpha))
    worst = max(worst, abs(float(share) / (weight / 0.001 / exact) - 1))
check("disc_on_bed share --onto disc: W/U over the exact resistance with the reduced radius, a disc closing on a disc "
      "twice its size at 1 mm/s along a slanted line (%d rows, worst %.2g)" % (len(rows), worst),
      r.returncode == 0 and len(rows) == gaps_passed and worst < 2e-3 and "reduced radius" in r.stdout,
      r.stdout + r.stderr)

# a disc 1 mm over the bed of a sheared channel (bed -5 mm/s, lid +5 mm/s, 0.1 m: shear 0.1 /s), moving at 1 mm/s
# over the bed and turning at -0.02 rad/s from 1.5 s on (earlier files at other speeds are left out)
d = folder("sheared", RUN_FILES)
write(os.path.join(d, "params.ini"), params_with(bottom_speed_mps=-0.005, top_speed_mps=0.005, height_m=0.1))
entries = []
for k, t in enumerate((1.0, 1.5, 2.0, 2.5)):
    f = "boulders_%09d.vtp" % k
    vx, omega = (-0.003, -0.05) if t < 1.5 else (-0.004, -0.02)
    vtp.write_vtp(os.path.join(d, f), np.array([[0.1, 0.0135]]), {"radius_m": np.array([0.0125]),
                  "velocity_mps": np.array([[vx, 0.0]]), "omega_radps": np.array([omega])}, t, k)
    entries.append((t, f))
vtp.write_pvd(os.path.join(d, "boulders.pvd"), entries)
r = tool(DB, "sheared", d)
check("disc_on_bed sheared: 3 files from 1.5 s, gap/a 0.08, (V - u_bed)/(shear a) 0.8, omega/shear -0.2",
      r.returncode == 0 and "3 disc files" in r.stdout and "gap/a 0.0800" in r.stdout and "shear a) 0.8000" in r.stdout
      and "omega/shear -0.2000" in r.stdout, r.stdout + r.stderr)
write(os.path.join(d, "params.ini"), params_with(bottom_speed_mps=0.005, top_speed_mps=0.005, height_m=0.1))
expect("disc_on_bed sheared: a channel that is not sheared", tool(DB, "sheared", d), "not sheared")
expect("disc_on_bed sheared: a run without discs", tool(DB, "sheared", folder("sheared_no_discs", RUN_FILES)),
       "boulders.pvd")

# a heavy disc (density ratio 1e4) a quarter radius over the bed, its spin decaying as exp(-2 t): from 0.3 to 1 s
# four files, R = I k over 4 pi mu a^2 and the exact coth alpha = 5/3 (cosh alpha = 1.25); files outside the window
# (a spin of 7 rad/s at 0.2 and 1.2 s) are left out
def spinning(name, spin_of_t, times=(0.2, 0.3, 0.5, 0.7, 1.0, 1.2), ratio=10000):
    d = folder(name, RUN_FILES)
    write(os.path.join(d, "params.ini"), params_with(density_ratio=ratio))
    entries = []
    for k, t in enumerate(times):
        f = "boulders_%09d.vtp" % k
        omega = spin_of_t(t) if 0.3 <= t <= 1.0 else 7.0
        vtp.write_vtp(os.path.join(d, f), np.array([[0.1, 0.015625]]), {"radius_m": np.array([0.0125]),
                      "velocity_mps": np.array([[1e-6, 0.0]]), "omega_radps": np.array([omega])}, t, k)
        entries.append((t, f))
    vtp.write_pvd(os.path.join(d, "boulders.pvd"), entries)
    return d


d = spinning("spin", lambda t: np.exp(-2 * t))
rp = RunParams(d)
resistance = 0.5 * 1e4 * 0.0125 ** 2 * 2 / (4 * rp.positive("fluid", "viscosity_m2ps"))  # I k / (4 pi rho nu a^2)
r = tool(DB, "spin", d)
check("disc_on_bed spin: 4 files from 0.3 to 1 s, gap/a 0.25, R = I k over 4 pi mu a^2 (%.4f), coth alpha 5/3"
      % resistance, r.returncode == 0 and "4 disc files" in r.stdout and "gap/a 0.2500" in r.stdout and
      "R/(4 pi mu a^2) %.4f" % resistance in r.stdout and "coth alpha 1.6667" in r.stdout and
      "R/exact %.4f" % (resistance / (5 / 3)) in r.stdout, r.stdout + r.stderr)
def sliding(name, speed_of_t):
    d = spinning(name, lambda t: 0.0)
    entries = []
    for k, (t, f) in enumerate(vtp.read_pvd(os.path.join(d, "boulders.pvd"))):
        vtp.write_vtp(os.path.join(d, f), np.array([[0.1, 0.015625]]), {"radius_m": np.array([0.0125]),
                      "velocity_mps": np.array([[speed_of_t(t), 0.0]]), "omega_radps": np.array([1e-6])}, t, k)
        entries.append((t, f))
    return d


# the same disc sliding at 0.01 exp(-3 t) m/s: R = m k over 4 pi mu, coth alpha - 1 = 2/3
resistance = 1e4 * 0.0125 ** 2 * 3 / (4 * rp.positive("fluid", "viscosity_m2ps"))  # m k / (4 pi rho nu)
r = tool(DB, "slide", sliding("slide", lambda t: 0.01 * np.exp(-3 * t) if 0.3 <= t <= 1.0 else 0.5))
check("disc_on_bed slide: 4 files from 0.3 to 1 s, R = m k over 4 pi mu (%.4f), coth alpha - 1 2/3" % resistance,
      r.returncode == 0 and "4 disc files" in r.stdout and "R/(4 pi mu) %.4f" % resistance in r.stdout and
      "coth alpha - 1 0.6667" in r.stdout, r.stdout + r.stderr)
expect("disc_on_bed slide: a disc given no speed", tool(DB, "slide", spinning("slide_none", lambda t: 1.0)),
       "x speed does not decay")
expect("disc_on_bed spin: a spin that grows", tool(DB, "spin", spinning("spin_grows", lambda t: np.exp(t))),
       "does not decay")
expect("disc_on_bed spin: a disc that does not turn", tool(DB, "spin", spinning("spin_none", lambda t: 0.0)),
       "zero or changes sign")
expect("disc_on_bed spin: two files in the window",
       tool(DB, "spin", spinning("spin_short", lambda t: np.exp(-t), times=(0.1, 0.4, 0.9, 1.5))), "the fit needs 3")
expect("disc_on_bed spin: a run without discs", tool(DB, "spin", folder("spin_no_discs", RUN_FILES)), "boulders.pvd")

# ---- 9. surge_watch ----
SW = "surge_watch.py"
expect("surge_watch -e foo", tool(SW, "-e", "foo", "--record", path("rec")), "endpoint", "foo")
expect("surge_watch --record onto a file", tool(SW, "--record", path("run", "params.ini")), "--record",
       "not a folder")
expect("surge_watch --png into a missing folder", tool(SW, "--png", path("nowhere", "live.png")), "--png")
expect("surge_watch --duration 0", tool(SW, "--record", path("rec"), "--duration", "0"), "--duration")
r = tool(SW, "-e", "ipc://" + path("nobody.sock"), "--record", path("rec"), "--duration", "0.3")
check("surge_watch says what it waits for, and fails when nothing came", r.returncode == 1 and "waiting" in r.stderr
      and "nobody.sock" in r.stderr and "no state received" in r.stderr, r.stderr.strip())
pub = "ipc://" + path("pub.sock")
r = with_peer(pub, zmq.PUB, [b"stats", b"not json"],
              lambda: tool(SW, "-e", pub, "--record", path("rec"), "--duration", "20"))
expect("surge_watch: a publisher sending garbage", r, "bad message", "JSON")

# ---- 10. stream_bench and render_bench ----
expect("stream_bench --surge missing", tool("stream_bench.py", "--surge", path("no_surge")), "--surge")
expect("stream_bench --out a file", tool("stream_bench.py", "--out", path("run", "params.ini")), "--out")
expect("stream_bench --end-s 0", tool("stream_bench.py", "--end-s", "0"), "--end-s")
# a surge that exits at startup: stream_bench gives its message (a resume sent to it would time out with another
# message) and starts no further run
counting = script("surge_counting", 'echo call >> "%s"\necho "surge: bad option (stand-in)" >&2\nexit 2\n'
                  % path("surge_calls.txt"))
r = tool("stream_bench.py", "--surge", counting, "--out", path("sb"), "--repeat", "1")
expect("stream_bench: surge exits at startup: its message", r, "surge: bad option (stand-in)")
calls = open(path("surge_calls.txt")).read().count("call") if os.path.exists(path("surge_calls.txt")) else 0
check("stream_bench: surge exiting at startup stops the benchmark after that one run", calls == 1,
      "%d runs started" % calls)
expect("render_bench --surge a folder", tool(RB, "--surge", WORK), "--surge")
BUILD = os.path.dirname(SURGE)
expect("ab_bench --base not a commit", tool(AB, "--new", BUILD, "--base", "no-such-commit"),
       "--base", "no-such-commit")
expect("ab_bench --new without surge-bench", tool(AB, "--new", WORK), "surge-bench")
expect("ab_bench --ch 0", tool(AB, "--new", BUILD, "--ch", "1.0,0"), "--ch")
expect("ab_bench --threads x", tool(AB, "--new", BUILD, "--threads", "x"), "--threads")
expect("ab_bench --pairs 0", tool(AB, "--pairs", "0"), "--pairs")
expect("ab_bench --set-b without =", tool(AB, "--new", BUILD, "--set-b", "numerics.cfl"), "--set-b")
expect("scaling --max-threads 0", tool(SC, "--max-threads", "0"), "--max-threads", "0")
expect("scaling --max-threads x", tool(SC, "--max-threads", "x"), "--max-threads", "'x'")
expect("scaling --max-threads 1.5", tool(SC, "--max-threads", "1.5"), "--max-threads", "1.5")
expect("scaling --threads 2,4", tool(SC, "--threads", "2,4"), "--threads", "2,4")
expect("scaling --threads 1,4,2", tool(SC, "--threads", "1,4,2"), "--threads", "rising")
expect("scaling --threads 1,x", tool(SC, "--threads", "1,x"), "--threads", "'1,x'")
expect("scaling --threads with --max-threads", tool(SC, "--threads", "1,2", "--max-threads", "2"), "--threads",
       "--max-threads")
expect("scaling --scene unknown", tool(SC, "--scene", "film,nope"), "--scene", "nope")
expect("scaling --quick with --scene", tool(SC, "--quick", "--scene", "film"), "--quick", "--scene")
expect("scaling --bench a folder", tool(SC, "--bench", WORK), "--bench")


def bench(*args):
    """Runs build/surge-bench with args (bad ones: it must refuse before it runs anything)."""
    return subprocess.run([os.path.join(BUILD, "surge-bench")] + list(args), capture_output=True, text=True,
                          timeout=60, stdin=subprocess.DEVNULL)


expect("surge-bench --threads 0", bench("--threads", "0"), "--threads")
expect("surge-bench --end-s nan", bench("--end-s", "nan"), "--end-s")
expect("surge-bench --ch 0", bench("--ch", "0"), "numerics.ch")
expect("surge-bench -s an unknown parameter", bench("--ch", "1.8", "-s", "numerics.no_such=1"), "numerics.no_such")
expect("surge-bench --layers without a value", bench("--layers"), "--layers")
expect("surge-bench a case that does not exist", bench(path("no_case.ini"), "--ch", "1.8"), "no_case.ini")

# ---- 11. surgectl ----
ctl = "ipc://" + path("ctl.sock")
expect("surgectl: a reply that is not a JSON object",
       with_peer(ctl, zmq.REP, [b"[1, 2]"], lambda: tool("surgectl", "-e", ctl, "-t", "5", "status")),
       "unexpected reply", rc=3)
expect("surgectl list: a reply without params",
       with_peer(ctl, zmq.REP, [json.dumps({"ok": True}).encode()],
                 lambda: tool("surgectl", "-e", ctl, "-t", "5", "list")),
       "unexpected reply", "params", rc=3)
expect("surgectl -t nan", tool("surgectl", "-t", "nan", "status"), "--timeout")

# ---- 12. freydier_metrics ----
no_wall = folder("no_wall", RUN_FILES)
write(os.path.join(no_wall, "params.ini"), params_with(upstream="false"))
expect("freydier_metrics: no upstream wall", tool("freydier_metrics.py", no_wall), "walls.upstream")
expect("freydier_metrics --png a folder", tool("freydier_metrics.py", path("run"), "--png", WORK), "--png")

# ---- 13. make_colormaps ----
expect("make_colormaps with an argument", tool("make_colormaps.py", "extra"), "unrecognized arguments")
# ---- 13b. spreading ----
expect("spreading measure: not a run folder", tool(SP, "measure", WORK), WORK)
expect("spreading reference --times-s 5,2 (not ascending)", tool(SP, "reference", path("run"), "--times-s", "5,2"),
       "--times-s")
expect("spreading reference --times-s x", tool(SP, "reference", path("run"), "--times-s", "x"), "--times-s")
sloped = folder("sloped", RUN_FILES)
write(os.path.join(sloped, "params.ini"), params_with(slope_deg="5"))
expect("spreading reference: a sloped bed", tool(SP, "reference", sloped), "slope_deg")
expect("spreading measure: a sloped bed", tool(SP, "measure", sloped), "slope_deg")
expect("spreading rows: not a run folder", tool(SP, "rows", WORK), WORK)
expect("spreading rows --time-s -1", tool(SP, "rows", path("run"), "--time-s", "-1"), "--time-s")

# ---- 14. every tool that prints a table, into a reader that stopped early (| head): no traceback ----
for name, *args in (("make_colormaps.py",), ("wall_contact.py", path("run"), "--after-s", "0.1"),
                    ("operator_check.py", path("run"), "--x", "0.06", "0.12", "--y", "0.004", "0.011")):
    p = subprocess.Popen([sys.executable, os.path.join(TOOLS, name)] + list(args), stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    p.stdout.close()  # before it writes
    err = p.stderr.read().decode()
    p.wait(60)
    check("%s into a closed pipe: no traceback" % name, "Traceback" not in err and p.returncode == 1,
          "rc %d, stderr: %s" % (p.returncode, err[-600:]))

sys.exit(finish())
