"""Helpers shared by the study drivers (freydier_convergence.py, stability_map.py): option parsing, errors and
the append-only CSV tables they write."""
import csv
import os
import sys


def fail(program, message):
    """One-line error on stderr, exit status 2 (bad input)."""
    print("%s: %s" % (program, message), file=sys.stderr)
    sys.exit(2)


def positive_numbers(program, text, option):
    """Comma-separated positive numbers of --option, or a clear error."""
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        fail(program, "--%s: expected comma-separated numbers, got '%s'" % (option, text))
    if not values or any(v <= 0 for v in values):
        fail(program, "--%s: expected positive numbers, got '%s'" % (option, text))
    return values


def append_row(csv_path, columns, row):
    """Appends row to the CSV table, writing the header when the file is new."""
    new = not os.path.isfile(csv_path)
    os.makedirs(os.path.dirname(os.path.abspath(csv_path)), exist_ok=True)
    with open(csv_path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=columns)
        if new:
            writer.writeheader()
        writer.writerow(row)


def solver_environment():
    """The environment for surge runs: idle OpenMP threads sleep instead of spinning (OMP_WAIT_POLICY=PASSIVE,
    unless set), so a run sharing its cores with other work does not slow down several-fold."""
    env = dict(os.environ)
    env.setdefault("OMP_WAIT_POLICY", "PASSIVE")
    return env


def read_rows(tool, csv_path):
    """The rows of a study's CSV table; fails with a message naming the file when it is missing or empty."""
    if not os.path.isfile(csv_path):
        fail(tool, "%s: no such file" % csv_path)
    with open(csv_path) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        fail(tool, "%s: no rows" % csv_path)
    return rows
