#!/usr/bin/python3
"""The scaling benchmark (bench/scaling.py) end to end on its tiny scene (--quick): the machine's lines, the table's
columns and rows (each scheme on 1 and 2 threads, the same steps on both, 1.00 the 1-thread speed-up), the per-phase
tables, and OMP_WAIT_POLICY=PASSIVE in every run it starts unless the caller set OMP_WAIT_POLICY or
GOMP_SPINCOUNT (ACTIVE kept, with --max-threads 1: one thread only). Then a surge-bench that fails:
its rows say so and the exit status is 1. The runs go through a stand-in surge-bench that records the two variables
and runs the real one. No figure is checked
against a bound: the timings only have to be there and be numbers.

usage: test_scaling.py SURGE_BENCH SOURCE_DIR WORK_DIR
"""
import os
import re
import shutil
import subprocess
import sys

from checks import check, finish

BENCH, SOURCE, WORK = sys.argv[1:4]
SCALING = os.path.join(SOURCE, "bench", "scaling.py")
COLUMNS = ["scene", "scheme", "fluid", "threads", "steps", "wall_s", "rate", "speed-up", "serial", "karp-flatt",
           "largest phase"]
PHASES = {"neighbours", "interaction", "boundary", "discs", "contacts", "geometry", "surface", "assembly", "multigrid",
          "viscous_solve", "pressure_solve", "disc_coupling", "update", "other"}
NUMBER = re.compile(r"^[0-9]+(\.[0-9]+)?$")


def stand_in(name, body):
    """An executable shell script WORK/name."""
    path = os.path.join(WORK, name)
    with open(path, "w") as f:
        f.write("#!/bin/sh\n" + body)
    os.chmod(path, 0o755)
    return path


def scaling(bench, *args, policy=None):
    """bench/scaling.py --bench bench args, with OMP_WAIT_POLICY=policy (None: unset) and GOMP_SPINCOUNT unset."""
    env = {k: v for k, v in os.environ.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
    if policy:
        env["OMP_WAIT_POLICY"] = policy
    return subprocess.run([sys.executable, SCALING, "--bench", bench] + list(args), capture_output=True, text=True,
                          env=env, timeout=600, stdin=subprocess.DEVNULL)


def table(stdout):
    """The header's cells and the rows' cells (split at runs of two or more spaces) of the main table."""
    lines = stdout.splitlines()
    starts = [i for i, line in enumerate(lines) if line.startswith("scene ")]
    if len(starts) != 1:
        return None, []
    rows = []
    for line in lines[starts[0] + 1:]:
        if not line.strip():
            break
        rows.append(re.split(r"\s{2,}", line.strip()))
    return re.split(r"\s{2,}", lines[starts[0]].strip()), rows


def policies(path):
    with open(path) as f:
        return f.read().split()


shutil.rmtree(WORK, ignore_errors=True)
os.makedirs(WORK)
record = os.path.join(WORK, "policies.txt")
recording = stand_in("surge-bench", 'echo "${OMP_WAIT_POLICY:-unset}/${GOMP_SPINCOUNT:-unset}" >> "%s"\n'
                                    'exec "%s" "$@"\n' % (record, BENCH))

# ---- the tiny scene, OMP_WAIT_POLICY and GOMP_SPINCOUNT unset ----
r = scaling(recording, "--quick")
check("--quick: exit status 0", r.returncode == 0, "rc %d, stderr: %s" % (r.returncode, r.stderr[-1500:]))
out = r.stdout
machine = re.search(r"^# machine: (.+), (\d+|unknown) physical cores, (\d+) logical CPUs, (\d+) usable", out, re.M)
check("the machine's line names the CPU and its cores", machine is not None and machine.group(1).strip() != "", out)
check("the OpenMP line: OMP_WAIT_POLICY=PASSIVE set by the benchmark, GOMP_SPINCOUNT unset, OMP_PROC_BIND named",
      re.search(r"^# OpenMP: OMP_WAIT_POLICY=PASSIVE, GOMP_SPINCOUNT=unset \(set by scaling.py\), OMP_PROC_BIND=\S+",
                out, re.M) is not None, out)
seen = policies(record)
check("every run got OMP_WAIT_POLICY=PASSIVE and no spin count (4 runs)", seen == ["PASSIVE/unset"] * 4, seen)
header, rows = table(out)
check("the table's columns", header == COLUMNS, header)
keys = [(row[0], row[1], row[3]) for row in rows]
check("the rows: the tiny scene, each scheme on 1 and 2 threads",
      keys == [("tiny", "explicit", "1"), ("tiny", "explicit", "2"), ("tiny", "implicit", "1"),
               ("tiny", "implicit", "2")], keys)
for row in rows:
    name = "row %s" % " ".join(row[:4])
    if not check(name + ": 11 cells", len(row) == len(COLUMNS), row):
        continue
    cells = dict(zip(COLUMNS, row))
    numbers = all(NUMBER.match(cells[c]) for c in ("fluid", "steps", "wall_s", "rate", "speed-up", "serial"))
    check(name + ": numbers where figures go", numbers, row)
    if not numbers:
        continue
    check(name + ": particles, steps, time and rate above zero",
          int(cells["fluid"]) > 0 and int(cells["steps"]) > 0 and float(cells["wall_s"]) > 0 and
          float(cells["rate"]) > 0, row)
    check(name + ": the serial fraction within [0, 1]", 0 <= float(cells["serial"]) <= 1, row)
    one = cells["threads"] == "1"
    check(name + ": speed-up 1.00 and no Karp-Flatt figure on 1 thread, a number on 2",
          (cells["speed-up"] == "1.00" and cells["karp-flatt"] == "-") if one else
          re.match(r"^-?[0-9]+\.[0-9]+$", cells["karp-flatt"]) is not None, row)
    largest = re.match(r"^(\w+) ([0-9]+) %$", cells["largest phase"])
    check(name + ": the largest phase is a phase, with its share",
          largest is not None and largest.group(1) in PHASES and int(largest.group(2)) <= 100, row)
if len(rows) == 4 and all(len(row) == len(COLUMNS) for row in rows):
    check("the same steps on 1 and 2 threads (each scheme)", rows[0][4] == rows[1][4] and rows[2][4] == rows[3][4],
          rows)
    check("the same fluid particles in every row", len({row[2] for row in rows}) == 1, rows)

# the per-phase tables: one per scheme, a column per thread count, phases the scheme has
for scheme, own, foreign in (("explicit", "interaction", "pressure_solve"), ("implicit", "pressure_solve",
                                                                             "interaction")):
    found = re.search(r"^# tiny %s, \d+ fluid particles: seconds per phase.*\n(.*\n(?:.+\n)+)" % scheme, out, re.M)
    if not check("the %s phase table is there" % scheme, found is not None, out):
        continue
    lines = found.group(1).splitlines()
    names = [line.split()[0] for line in lines[1:]]
    check("the %s phase table: columns for 1 and 2 threads" % scheme, lines[0].split()[:5] ==
          ["phase", "1", "thr", "2", "thr"], lines[0])
    check("the %s phase table: known phases, %s and other among them, not %s, then the total" % (scheme, own, foreign),
          set(names[:-1]) <= PHASES and own in names and "other" in names and foreign not in names and
          names[-1] == "total", names)

# ---- OMP_WAIT_POLICY set by the caller, one thread ----
os.remove(record)
r = scaling(recording, "--quick", "--max-threads", "1", policy="ACTIVE")
check("--max-threads 1, ACTIVE: exit status 0", r.returncode == 0, "rc %d, stderr: %s" % (r.returncode, r.stderr))
check("the caller's OMP_WAIT_POLICY is named as the caller's",
      "OMP_WAIT_POLICY=ACTIVE, GOMP_SPINCOUNT=unset (set by the caller)" in r.stdout, r.stdout)
seen = policies(record)
check("every run kept the caller's ACTIVE and no spin count was added (2 runs)", seen == ["ACTIVE/unset"] * 2, seen)
header, rows = table(r.stdout)
check("--max-threads 1: rows on 1 thread only", [row[3] for row in rows] == ["1", "1"], rows)

# ---- the implicit scheme's multigrid parts: each run's thread count, the implicit runs only ----
arguments = os.path.join(WORK, "arguments.txt")
logging = stand_in("logging-bench", 'echo "$*" >> "%s"\nexec "%s" "$@"\n' % (arguments, BENCH))
r = scaling(logging, "--quick", "--multigrid-parts", "threads")
check("--multigrid-parts threads: exit status 0", r.returncode == 0, "rc %d, stderr: %s" % (r.returncode, r.stderr))
check("--multigrid-parts threads: named in the header", "# implicit.multigrid_parts = the run's thread count" in r.stdout,
      r.stdout)
with open(arguments) as f:
    calls = f.read().splitlines()
parts_given = [(re.search(r"numerics\.scheme=(\w+)", c).group(1), re.search(r"--threads (\d+)", c).group(1),
                (re.search(r"implicit\.multigrid_parts=(\d+)", c) or re.match("()", "")).group(1)) for c in calls]
check("--multigrid-parts threads: the implicit runs get their thread count as parts, the explicit ones none",
      parts_given == [("explicit", "1", ""), ("explicit", "2", ""), ("implicit", "1", "1"), ("implicit", "2", "2")],
      parts_given)
r = scaling(BENCH, "--quick", "--multigrid-parts", "many")
check("--multigrid-parts many: refused (exit status 2), the value named",
      r.returncode == 2 and "expected a whole number >= 1 or 'threads', got 'many'" in r.stderr, r.stderr)

# ---- one scheme ----
os.remove(arguments)
r = scaling(logging, "--quick", "--scheme", "implicit")
with open(arguments) as f:
    schemes = [re.search(r"numerics\.scheme=(\w+)", c).group(1) for c in f.read().splitlines()]
check("--scheme implicit: exit status 0, the implicit runs only (2)", r.returncode == 0 and schemes == ["implicit"] * 2,
      "rc %d, schemes %s, stderr: %s" % (r.returncode, schemes, r.stderr))
r = scaling(BENCH, "--quick", "--scheme", "semi-implicit")
check("--scheme semi-implicit: refused (exit status 2), the value named",
      r.returncode == 2 and "expected comma-separated names among explicit, implicit, got 'semi-implicit'" in r.stderr,
      r.stderr)

# ---- a surge-bench that fails ----
failing = stand_in("failing-bench", 'echo "surge-bench: stand-in failure"\nexit 1\n')
r = scaling(failing, "--quick")
header, rows = table(r.stdout)
check("a failing surge-bench: exit status 1", r.returncode == 1, "rc %d, stderr: %s" % (r.returncode, r.stderr))
check("a failing surge-bench: every row says failed, with its message",
      len(rows) == 4 and all(row[-1].startswith("failed: exit status 1: surge-bench: stand-in failure")
                             for row in rows), rows)
check("a failing surge-bench: no traceback", "Traceback" not in r.stderr, r.stderr)

sys.exit(finish())
