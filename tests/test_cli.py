#!/usr/bin/python3
"""Command-line tests of the surge program: errors for bad input, the health monitor, restarts.

Usage: test_cli.py SURGE_BINARY SOURCE_DIR WORK_DIR GROUP
  GROUP inputs   every kind of bad case file and bad option gets its own clear error (exit 2 or 3, never a
                 crash, never exit 0); `surge check` accepts every shipped case; `surge params` documents
                 every key the cases use; every --help prints usage.
  GROUP blowup   an absurd fixed time step makes the health monitor stop the run (exit 1) with a clear
                 message, a finite last_good.vtp, its checkpoint last_good.bin (an earlier periodic
                 checkpoint.bin kept) and clean diagnostics; the same case with its normal time step runs healthy.
  GROUP restart  `surge run --restart` continues to the same state hash as an uninterrupted run; the run
                 folder's run.pvd and diagnostics.csv cover both halves; the hash does not depend on the
                 thread count.

Each check prints one line, "name: ok" or "name: FAILED" followed by the command, exit code and stderr.
The script exits 1 if any check failed. Every subprocess has a timeout: a hang is a failure.
Python 3 standard library + numpy only.
"""

import csv
import math
import os
import re
import shlex
import shutil
import signal
import struct
import subprocess
import sys
import time

import numpy as np

QUICK_TIMEOUT_S = 30   # commands that fail or finish before stepping
RUN_TIMEOUT_S = 90     # short simulations (a few seconds each on 2 cores)

failures = []
SURGE = SOURCE = WORK = None


class Result:
    def __init__(self, args, rc, stdout, stderr, timed_out):
        self.args, self.rc, self.stdout, self.stderr, self.timed_out = args, rc, stdout, stderr, timed_out

    def describe(self):
        if self.timed_out:
            code = "none (timed out)"
        elif self.rc < 0:
            code = "%d (killed by signal %d)" % (self.rc, -self.rc)
        else:
            code = str(self.rc)
        lines = ["    command: %s" % shlex.join(self.args), "    exit code: %s" % code]
        err = self.stderr.rstrip("\n")
        if len(err) > 3000:
            err = err[:1500] + "\n... (%d characters left out) ...\n" % (len(err) - 3000) + err[-1500:]
        lines.append("    stderr: " + (err.replace("\n", "\n            ") if err else "(empty)"))
        out = self.stdout.rstrip("\n")
        if out and len(out) < 2000:
            lines.append("    stdout: " + out.replace("\n", "\n            "))
        return "\n".join(lines)


# Idle OpenMP threads sleep instead of spinning: on a loaded 2-core machine (ctest -j, other builds) spinning
# threads make a 1 s run take 10 s or more. Results do not depend on it (the restart group checks that the
# hash does not depend on the thread count).
ENV = dict(os.environ)
ENV.setdefault("OMP_WAIT_POLICY", "PASSIVE")


def surge(*args, timeout=QUICK_TIMEOUT_S, cwd=None):
    """Runs the surge binary; never raises for a bad exit, a signal or a hang."""
    argv = [SURGE] + [str(a) for a in args]
    try:
        p = subprocess.run(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           timeout=timeout, cwd=cwd or WORK, env=ENV)
        return Result(argv, p.returncode, p.stdout.decode("utf-8", "replace"),
                      p.stderr.decode("utf-8", "replace"), False)
    except subprocess.TimeoutExpired as e:
        def text(b):
            return b.decode("utf-8", "replace") if isinstance(b, bytes) else (b or "")
        return Result(argv, None, text(e.stdout), text(e.stderr), True)


def report(name, ok, result=None, detail=None):
    """Prints one line per check; on failure, the reason and the command with its exit code and stderr."""
    if ok:
        print("%s: ok" % name)
        return True
    failures.append(name)
    print("%s: FAILED%s" % (name, (" - " + detail) if detail else ""))
    if result is not None:
        print(result.describe())
    sys.stdout.flush()
    return False


def exited(r, code):
    return not r.timed_out and r.rc == code


def missing_text(text, wanted):
    return [w for w in wanted if w not in text]


def expect_error(name, args, wanted, code=2, stream="stderr"):
    """The command must exit with `code` (not 0, not a signal, not a hang) and its stderr must contain every
    string in `wanted`."""
    r = surge(*args)
    problems = []
    if r.timed_out:
        problems.append("timed out after %d s" % QUICK_TIMEOUT_S)
    elif r.rc < 0:
        problems.append("crashed (signal %d)" % -r.rc)
    elif r.rc != code:
        problems.append("exit code %d, expected %d" % (r.rc, code))
    text = r.stderr if stream == "stderr" else r.stdout
    miss = missing_text(text, wanted)
    if miss:
        problems.append("%s lacks %s" % (stream, ", ".join(repr(m) for m in miss)))
    return report(name, not problems, r, "; ".join(problems))


def write_file(name, data):
    path = os.path.join(WORK, name)
    mode = "wb" if isinstance(data, bytes) else "w"
    with open(path, mode) as f:
        f.write(data)
    return path


def state_hash(r):
    """The hash on the final stderr line ("... state hash <16 hex digits> ..."), or None."""
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    if not lines:
        return None
    m = re.search(r"state hash ([0-9a-f]{16})\b", lines[-1])
    return m.group(1) if m else None


def case_lines(name):
    with open(os.path.join(SOURCE, "cases", name)) as f:
        return f.read().splitlines()


def parse_case(path):
    """(section, key) pairs of a shipped case file (comments '#'/';' stripped)."""
    pairs, section = [], None
    with open(path) as f:
        for line in f:
            line = re.split(r"[#;]", line, maxsplit=1)[0].strip()
            if not line:
                continue
            if line.startswith("["):
                section = line.strip("[]").strip()
            elif "=" in line:
                pairs.append((section, line.split("=", 1)[0].strip()))
    return pairs


# ---------------------------------------------------------------------------------------------------------
# GROUP inputs


def bad_case(name, lines, insert_at, bad_line, wanted_fn, also_run=True):
    """Writes `lines` with `bad_line` inserted so that it becomes line `insert_at` (1-based), then checks that
    `surge check` and `surge run` refuse it with exit 2 and a message containing wanted_fn(path, line_no)."""
    text_lines = list(lines)
    text_lines.insert(insert_at - 1, bad_line)
    path = write_file("case_%s.ini" % name, "\n".join(text_lines) + "\n")
    wanted = wanted_fn(path, insert_at)
    expect_error("case_%s_check" % name, ["check", path], wanted)
    if also_run:
        expect_error("case_%s_run" % name, ["run", path, "-s", "output.progress_interval_s=0", "-s", "time.end_s=0.001",
                                            "-o", os.path.join(WORK, "out_" + name)], wanted)


def cross_field(name, base, overrides, wanted):
    """A case file that parses but fails surge_params_validate, via the file and via -s overrides."""
    lines = case_lines(base)
    out, section = [], None
    pending = dict(overrides)
    for line in lines:
        s = line.split("#")[0].split(";")[0].strip()
        if s.startswith("["):
            section = s.strip("[]").strip()
        elif "=" in s and section:
            key = "%s.%s" % (section, s.split("=", 1)[0].strip())
            if key in pending:
                line = "%s = %s" % (key.split(".")[1], pending.pop(key))
        out.append(line)
    for key, value in pending.items():  # keys the base file does not set: append their sections
        sec, k = key.split(".")
        out += ["[%s]" % sec, "%s = %s" % (k, value)]
    path = write_file("cross_%s.ini" % name, "\n".join(out) + "\n")
    expect_error("cross_%s_file" % name, ["check", path], wanted + [path + ": "])
    sets = []
    for key, value in overrides.items():
        sets += ["-s", "%s=%s" % (key, value)]
    base_path = os.path.join(SOURCE, "cases", base)
    expect_error("cross_%s_override" % name, ["check", base_path] + sets,
                 wanted + [base_path + " with the -s overrides: "])


def group_inputs():
    cases_dir = os.path.join(SOURCE, "cases")
    tank = case_lines("still_tank.ini")
    # line numbers in still_tank.ini (1-based) used below: after "[domain]" and after "[numerics]"
    domain_line = tank.index("[domain]") + 1
    numerics_line = tank.index("[numerics]") + 1
    shifting_line = tank.index("[shifting]") + 1
    walls_line = tank.index("[walls]") + 1
    body_line = tank.index("[body]") + 1

    def at(path, n):
        return "%s:%d:" % (path, n)

    # --- case-file errors, each with file:line -------------------------------------------------------
    bad_case("unknown_section", tank, domain_line, "[nosuch]",
             lambda p, n: [at(p, n), "unknown section", "nosuch"])
    bad_case("unknown_key", tank, domain_line + 1, "colour_m = 3",
             lambda p, n: [at(p, n), "unknown key", "colour_m"])
    bad_case("not_a_number", tank, domain_line + 1, "length_m = 0.4m",
             lambda p, n: [at(p, n), "domain.length_m", "'0.4m'", "not a number"])
    bad_case("not_a_number_word", tank, numerics_line + 1, "cfl = fast",
             lambda p, n: [at(p, n), "numerics.cfl", "'fast'", "not a number"])
    bad_case("nan_value", tank, numerics_line + 1, "cfl = nan",
             lambda p, n: [at(p, n), "numerics.cfl", "not a number"])
    bad_case("out_of_range_real", tank, body_line + 1, "slope_deg = 95",
             lambda p, n: [at(p, n), "body.slope_deg", "out of range", "-89", "89"])
    bad_case("out_of_range_real2", tank, numerics_line + 1, "ch = 10",
             lambda p, n: [at(p, n), "numerics.ch", "out of range", "[0.5, 4]"])
    bad_case("out_of_range_int", tank, walls_line + 1, "layers = 17",
             lambda p, n: [at(p, n), "walls.layers", "out of range", "[0, 16]"])
    bad_case("not_an_integer", tank, walls_line + 1, "layers = 6.5",
             lambda p, n: [at(p, n), "walls.layers", "not an integer"])
    bad_case("bad_boolean", tank, domain_line + 1, "periodic_x = maybe",
             lambda p, n: [at(p, n), "domain.periodic_x", "'maybe'", "true or false"])
    bad_case("bad_enum", tank, shifting_line + 1, "form = sideways",
             lambda p, n: [at(p, n), "shifting.form", "'sideways'", "none|velocity|lind"])
    bad_case("no_equals", tank, domain_line + 1, "length_m 0.4",
             lambda p, n: [at(p, n), "key = value", "length_m 0.4"])
    bad_case("key_before_section", ["# a comment, then a key with no section"] + tank, 2, "length_m = 0.4",
             lambda p, n: [at(p, n), "length_m", "before any [section]"])
    bad_case("malformed_header_unclosed", tank, numerics_line + 1, "[time",
             lambda p, n: [at(p, n), "malformed section header", "[time"])
    bad_case("malformed_header_trailing", tank, numerics_line + 1, "[time] end_s = 1",
             lambda p, n: [at(p, n), "malformed section header"])
    bad_case("empty_value", tank, domain_line + 1, "length_m =",
             lambda p, n: [at(p, n), "domain.length_m", "empty value"])
    bad_case("empty_value_comment", tank, domain_line + 1, "height_m =   # forgot it",
             lambda p, n: [at(p, n), "domain.height_m", "empty value"])
    bad_case("long_line", tank, numerics_line + 1, "# " + "x" * 3000,
             lambda p, n: [at(p, n), "longer than"])
    bad_case("value_glued_semicolon", tank, domain_line + 1, "length_m = 0.4;0.5",
             lambda p, n: [at(p, n), "domain.length_m", "'0.4;0.5'", "not a number"])
    bad_case("list_glued_semicolon", tank + ["[boulders]", "placement = list"], len(tank) + 3,
             "list_m = 0.1 0.05 0.02; 0.25 0.05 0.02",  # ';' as a disc separator: refused, not one disc
             lambda p, n: [p, "boulders.list_m", "not a number"])
    # an error late in the file still names its own line (line counting is not thrown off by comments)
    bad_case("late_line_number", tank, len(tank) + 1, "bogus_key = 1",
             lambda p, n: [at(p, n), "bogus_key"])

    missing = os.path.join(WORK, "no_such_dir", "no_such_case.ini")
    expect_error("case_missing_file_check", ["check", missing], [missing, "cannot open"])
    expect_error("case_missing_file_run", ["run", missing, "-o", os.path.join(WORK, "out_missing")], [missing])
    binary = write_file("case_binary.ini", b"[domain]\nlength_m = 0.4\n\x00\x01\x02\xff\xfe garbage\x00\n")
    expect_error("case_binary_check", ["check", binary], [binary, "NUL"])
    expect_error("case_binary_run", ["run", binary, "-o", os.path.join(WORK, "out_binary")], [binary, "NUL"])
    folder = os.path.join(WORK, "a_folder.ini")
    os.makedirs(folder, exist_ok=True)
    expect_error("case_is_a_folder", ["check", folder], [folder])
    empty = write_file("case_empty.ini", "")
    r = surge("check", empty)
    report("case_empty_file_not_a_crash", not r.timed_out and r.rc in (0, 2), r,
           "an empty case file (all defaults) must be accepted or refused with exit 2")

    # files that are fine: CRLF line endings, a long comment just under the limit, comments with ';'
    crlf = write_file("case_crlf.ini", "\r\n".join(tank) + "\r\n")
    r = surge("check", crlf)
    report("case_crlf_accepted", exited(r, 0) and "ok" in r.stdout, r)
    under = list(tank)
    under.insert(numerics_line, "#" + "y" * 1000)
    path = write_file("case_long_comment.ini", "\n".join(under) + "\n")
    r = surge("check", path)
    report("case_1000_char_comment_accepted", exited(r, 0) and "ok" in r.stdout, r)

    # --- cross-field errors (surge_params_validate) ------------------------------------------------------
    cross_field("fluid_outside_domain", "still_tank.ini", {"fluid.x1_m": "0.5"},
                ["fluid block", "domain", "0.5", "0.4"])
    cross_field("x1_not_above_x0", "still_tank.ini", {"fluid.x0_m": "0.3", "fluid.x1_m": "0.2"},
                ["fluid.x1_m", "fluid.x0_m", "greater"])
    cross_field("x1_equal_x0", "still_tank.ini", {"fluid.x0_m": "0.2", "fluid.x1_m": "0.2"},
                ["fluid.x1_m", "fluid.x0_m"])
    # a dp that does not divide the period: moved to the nearest that does when that is 1 % or less (0.6011 m is
    # 300.55 spacings of 2 mm: 301 of 1.997 mm, 0.15 %), said, and run at it; refused, named, beyond 1 %
    # (0.0611 m is 30.55 spacings: 31 would move dp by 1.5 %)
    cross_field("periodic_length_not_dp_multiple", "belt_front.ini", {"domain.length_m": "0.0611", "fluid.x1_m": "0.05"},
                ["domain.length_m", "0.0611", "whole number", "dp", "30.55 of them", "31"])
    # the debris surge's case with only dp changed never fails its check: a dp that does not divide its
    # 33 m period is fitted, the wall layers and c0 follow dp, and discs are refused only below 3 dp across
    debris = os.path.join(SOURCE, "cases", "debris_surge.ini")
    discs = ["-s", "boulders.placement=graded", "-s", "boulders.count=28", "-s", "boulders.seed=1"]
    failed = []
    for dp in ("0.12", "0.08", "0.07", "0.066", "0.055", "0.045", "0.04", "0.035", "0.03", "0.022"):
        for extra in ([], discs) if float(dp) <= 0.2 / 3 else ([],):
            r = surge("check", debris, "-s", "numerics.dp_m=" + dp, *extra)
            if not exited(r, 0):
                failed.append("dp %s%s: %s" % (dp, " with discs" if extra else "", r.stderr.strip()[-300:]))
    report("debris_surge_any_dp_checks", not failed, None, "; ".join(failed))
    fitted_dir = os.path.join(WORK, "dp_fitted")
    r = surge("run", os.path.join(SOURCE, "cases", "belt_front.ini"), "-s", "domain.length_m=0.6011", "-s",
              "time.end_s=0.0005", "-o", fitted_dir, "--overwrite")
    params_path = os.path.join(fitted_dir, "params.ini")
    dp_line = re.search(r"^dp_m = (\S+)$", open(params_path).read(), re.M) if os.path.isfile(params_path) else None
    dp_run = float(dp_line.group(1)) if dp_line else float("nan")
    report("periodic_dp_fitted_to_length", exited(r, 0) and not missing_text(r.stderr, [
        "note: numerics.dp_m = 0.002 m does not divide the periodic domain.length_m = 0.6011 m", "301 spacings",
        "0.15 % finer"]) and abs(0.6011 / dp_run - 301) < 1e-9, r, "params.ini dp_m = %r" % dp_run)
    # the program and the machine: `surge version` names the source's commit (as git describes it), the compiler and
    # the vector extensions, and the CPU; every run's params.ini carries the same two lines
    r = surge("version")
    def git(*args):  # (exit status, output) of git in the source; 127 where there is no git program
        try:
            p = subprocess.run(["git", "-C", SOURCE] + list(args), capture_output=True, text=True, timeout=60)
            return p.returncode, p.stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return 127, ""
    status, described = git("describe", "--always", "--dirty", "--abbrev=12")
    commit = described if status == 0 and described else "unknown"
    program = re.search(r"^program: (surge (\d+\.\d+\.\d+)(?:\+(\S+))?, .+, vectors .+)$", r.stdout, re.M)
    machine = re.search(r"^machine: (.+)$", r.stdout, re.M)
    params_text = open(params_path).read() if os.path.isfile(params_path) else ""
    # the version is the build's (CMakeLists.txt's project()); the commit named after it is the checkout's, or (a build
    # older than the last commit) another commit of this repository, and none without git
    with open(os.path.join(SOURCE, "CMakeLists.txt")) as f:
        project_version = re.search(r"project\(surge VERSION (\S+)", f.read()).group(1)
    built = (program.group(3) or "unknown") if program else ""
    known = program is not None and program.group(2) == project_version and (
        built == commit or (built not in ("", "unknown") and
                            git("cat-file", "-e", built.split("-dirty")[0] + "^{commit}")[0] == 0))
    report("version_names_commit_compiler_vectors_machine", exited(r, 0) and program is not None and
           machine is not None and known, r, "git describe: %s, version %s" % (commit, project_version))
    expect_error("version_takes_no_arguments", ["version", "extra"], ["version takes no arguments"])
    expect_error("params_takes_no_arguments", ["params", "extra"], ["params takes no arguments"])
    report("params_ini_names_program_and_machine", program is not None and machine is not None and
           ("# program: %s\n" % program.group(1)) in params_text and ("# machine: %s\n" % machine.group(1)) in
           params_text, None, params_text[:400])
    cross_field("wall_layers_too_thin", "still_tank.ini", {"walls.layers": "2"},
                ["walls.layers", "2", "kernel support", "6"])
    cross_field("upstream_without_periodic", "still_tank.ini", {"walls.upstream": "true"},
                ["walls.upstream", "periodic"])
    cross_field("walls_too_many", "freydier_id1.ini", {"domain.length_m": "10000", "fluid.x1_m": "0.1"},
                ["walls would need about", "more than 5e7", "domain.length_m"])
    cross_field("cell_grid_too_large", "freydier_id1.ini", {"domain.length_m": "1000", "domain.height_m": "1000",
                                                            "numerics.dp_m": "0.002"},
                ["cell grid would have about", "more than 2e8"])

    # --- command line --------------------------------------------------------------------------------
    poiseuille = os.path.join(cases_dir, "poiseuille.ini")
    tank_case = os.path.join(cases_dir, "still_tank.ini")
    out = os.path.join(WORK, "out_cli")
    expect_error("cli_no_command", [], ["usage"])
    expect_error("cli_unknown_command", ["frobnicate"], ["unknown command", "frobnicate"])
    expect_error("cli_run_unknown_option", ["run", tank_case, "--bogus", "-o", out], ["unknown option", "--bogus"])
    expect_error("cli_check_unknown_option", ["check", tank_case, "--fast"], ["unknown option", "--fast"])
    expect_error("cli_check_rejects_o", ["check", tank_case, "-o", out], ["-o"])
    expect_error("cli_params_extra_argument", ["params", "extra"], ["params"])
    expect_error("cli_s_without_value", ["run", tank_case, "-o", out, "-s"], ["-s", "section.key=value"])
    expect_error("cli_s_unknown_key", ["run", tank_case, "-o", out, "-s", "domain.colour=3"],
                 ["unknown parameter", "domain.colour"])
    expect_error("cli_s_unknown_section", ["check", tank_case, "-s", "nosuch.key=3"],
                 ["unknown parameter", "nosuch.key"])
    expect_error("cli_s_no_equals", ["run", tank_case, "-o", out, "-s", "time.end_s"],
                 ["time.end_s", "section.key=value"])
    expect_error("cli_s_no_section", ["check", tank_case, "-s", "end_s=1"], ["end_s"])
    expect_error("cli_s_out_of_range", ["run", tank_case, "-o", out, "-s", "numerics.ch=10"],
                 ["numerics.ch", "out of range", "[0.5, 4]"])
    expect_error("cli_s_not_a_number", ["check", tank_case, "-s", "time.end_s=soon"],
                 ["time.end_s", "'soon'", "not a number"])
    expect_error("cli_s_empty_value", ["check", tank_case, "-s", "time.end_s="], ["time.end_s", "empty value"])
    expect_error("cli_s_bad_enum", ["check", tank_case, "-s", "shifting.form=wiggle"],
                 ["shifting.form", "none|velocity|lind"])
    expect_error("cli_threads_zero", ["run", tank_case, "-o", out, "--threads", "0"], ["--threads", "'0'", "[1, 1024]"])
    expect_error("cli_threads_abc", ["run", tank_case, "-o", out, "--threads", "abc"],
                 ["--threads", "'abc'", "[1, 1024]"])
    expect_error("cli_threads_negative", ["run", tank_case, "-o", out, "--threads", "-3"], ["--threads", "'-3'"])
    expect_error("cli_threads_without_value", ["run", tank_case, "-o", out, "--threads"], ["--threads"])
    expect_error("cli_o_without_value", ["run", tank_case, "-o"], ["-o", "output folder"])
    expect_error("cli_o_empty", ["run", tank_case, "-o", ""], ["-o", "output folder"])
    expect_error("cli_two_case_files", ["run", tank_case, poiseuille, "-o", out],
                 ["unexpected argument", poiseuille])
    expect_error("cli_check_two_case_files", ["check", tank_case, poiseuille], ["unexpected argument", poiseuille])
    expect_error("cli_check_without_case", ["check"], ["CASE"])
    expect_error("cli_restart_without_value", ["run", "--restart"], ["--restart", "checkpoint"])

    # a real checkpoint from a tiny run, and broken copies of it
    ck_dir = os.path.join(WORK, "ck_run")
    r = surge("run", poiseuille, "-s", "time.end_s=0.002", "-s", "output.progress_interval_s=0", "-o", ck_dir,
              timeout=RUN_TIMEOUT_S)
    checkpoint = os.path.join(ck_dir, "checkpoint.bin")
    have_ck = report("tiny_run_for_checkpoint", exited(r, 0) and os.path.isfile(checkpoint), r)
    if have_ck:
        # a restart into a folder whose time series has other columns (an earlier version's) is refused, the file
        # left as it was: appending rows of this version's columns would mix two tables in one file
        other = os.path.join(WORK, "ck_other_columns")
        shutil.rmtree(other, ignore_errors=True)
        shutil.copytree(ck_dir, other)
        series = os.path.join(other, "diagnostics.csv")
        with open(series) as f:
            rows = f.read().split("\n")
        edited = "\n".join(["time_s,step,dt_s,old_column"] + rows[1:])
        with open(series, "w") as f:
            f.write(edited)
        r = surge("run", "--restart", os.path.join(other, "checkpoint.bin"), "-o", other, "-s", "time.end_s=0.004",
                  timeout=RUN_TIMEOUT_S)
        with open(series) as f:
            kept = f.read() == edited
        report("restart_into_other_columns_refused", exited(r, 3) and kept and
               not missing_text(r.stderr, ["diagnostics.csv", "old_column", "-o"]), r)
    expect_error("cli_case_and_restart", ["run", tank_case, "--restart", checkpoint, "-o", out],
                 ["CASE", "--restart", "not both"])
    missing_ck = os.path.join(WORK, "no_such_checkpoint.bin")
    expect_error("cli_restart_missing_file", ["run", "--restart", missing_ck, "-o", out], [missing_ck])
    expect_error("cli_restart_case_file", ["run", "--restart", tank_case, "-o", out],
                 [tank_case, "not a surge checkpoint"])
    empty_ck = write_file("empty_checkpoint.bin", b"")
    expect_error("cli_restart_empty_file", ["run", "--restart", empty_ck, "-o", out],
                 [empty_ck, "not a surge checkpoint"])
    if have_ck:
        with open(checkpoint, "rb") as f:
            data = f.read()
        # cut in the header, in the parameter block, in the particle arrays, in the final hash
        for label, size, wanted in [("header", 12, "checkpoint"),
                                    ("params", 200, "truncated"),
                                    ("particles", len(data) // 2, "truncated"),
                                    ("hash", len(data) - 3, "truncated")]:
            path = write_file("truncated_%s.bin" % label, data[:size])
            expect_error("cli_restart_truncated_%s" % label,
                         ["run", "--restart", path, "-o", os.path.join(WORK, "out_trunc_" + label)], [path, wanted])
        # one flipped byte in the particle data: the stored hash must catch it
        # (layout: magic, u32 version, u32 real size, u64 params length, params, i64 step, 3 f64, 2 i32, x[f64]...)
        plen = struct.unpack_from("<Q", data, 16)[0]
        first_x = 24 + plen + 8 + 3 * 8 + 2 * 4
        corrupt = bytearray(data)
        corrupt[min(first_x + 8 * 10 + 2, len(data) - 1)] ^= 0x40  # a low mantissa byte of the 11th x
        path = write_file("corrupt_checkpoint.bin", bytes(corrupt))
        expect_error("cli_restart_corrupt_byte", ["run", "--restart", path, "-o", os.path.join(WORK, "out_corrupt")],
                     [path, "corrupt"])
        def fnv(raw):
            h = 14695981039346656037
            for byte in raw:
                h = ((h ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
            return h

        def resealed(raw):
            """The checkpoint with its version 4 checksum made to match (a deliberate edit), so that the checks
            behind the checksum are tested too."""
            raw = bytearray(raw)
            raw[-8:] = struct.pack("<Q", fnv(bytes(raw[:-8])))
            return bytes(raw)

        # edits outside the state hash: the parameters, the first time step, bytes appended
        text = bytes(data[24:24 + plen])
        edited = text.replace(b"viscosity_m2ps = ", b"viscosity_m2ps = 9", 1)
        corrupt = bytearray(data[:16]) + struct.pack("<Q", len(edited)) + edited + data[24 + plen:]
        path = write_file("edited_params_checkpoint.bin", bytes(corrupt))
        expect_error("cli_restart_edited_parameters", ["run", "--restart", path, "-o", os.path.join(WORK, "out_ep")],
                     [path, "checksum mismatch"])
        path = write_file("trailing_checkpoint.bin", bytes(data) + b"\0")
        expect_error("cli_restart_trailing_bytes", ["run", "--restart", path, "-o", os.path.join(WORK, "out_tb")],
                     [path, "bytes after the end"])
        corrupt = bytearray(data)
        corrupt[24 + plen + 24:24 + plen + 32] = struct.pack("<d", 0.0)
        path = write_file("zero_first_dt_checkpoint.bin", resealed(corrupt))
        expect_error("cli_restart_zero_first_dt", ["run", "--restart", path, "-o", os.path.join(WORK, "out_fd")],
                     [path, "corrupt step, time or time step"])
        # a NaN time step (outside the state hash) is refused by name
        corrupt = bytearray(data)
        corrupt[24 + plen + 16:24 + plen + 24] = struct.pack("<d", float("nan"))
        path = write_file("nan_dt_checkpoint.bin", resealed(corrupt))
        expect_error("cli_restart_nan_dt", ["run", "--restart", path, "-o", os.path.join(WORK, "out_nan_dt")],
                     [path, "corrupt step, time or time step"])
        # a repeated fluid id under a state hash made to match is still refused (the ids must be a permutation)
        real_size = struct.unpack_from("<I", data, 12)[0]
        count, wall_count = struct.unpack_from("<ii", data, 24 + plen + 32)
        fluid = count - wall_count
        first_id = first_x + fluid * (2 * 8 + 3 * real_size)
        corrupt = bytearray(data)
        corrupt[first_id + 4:first_id + 8] = corrupt[first_id:first_id + 4]
        hashed = bytes(corrupt[24 + plen:24 + plen + 16]) + bytes(corrupt[first_x:first_id + 4 * fluid])
        corrupt[-16:-8] = struct.pack("<Q", fnv(hashed))  # the state hash, before the checksum
        path = write_file("repeated_id_checkpoint.bin", resealed(corrupt))
        expect_error("cli_restart_repeated_id", ["run", "--restart", path, "-o", os.path.join(WORK, "out_rep_id")],
                     [path, "corrupt particle ids", "repeated"])
    expect_error("cli_restart_non_live_override",
                 ["run", "--restart", checkpoint, "-s", "numerics.dp_m=0.001", "-o", os.path.join(WORK, "out_nl")],
                 ["numerics.dp_m", "restart"])
    expect_error("cli_restart_override_unknown_key",
                 ["run", "--restart", checkpoint, "-s", "time.finish=1", "-o", os.path.join(WORK, "out_nl")],
                 ["time.finish"])
    expect_error("cli_restart_override_out_of_range",
                 ["run", "--restart", checkpoint, "-s", "fluid.viscosity_m2ps=-1", "-o", os.path.join(WORK, "out_nl")],
                 ["fluid.viscosity_m2ps", "out of range"])

    # -o under a regular file (output error, exit 3, names the path), and -o naming a regular file
    regular = write_file("a_regular_file", "not a folder\n")
    under_file = os.path.join(regular, "sub")
    expect_error("cli_output_under_regular_file",
                 ["run", poiseuille, "-s", "time.end_s=0.002", "-s", "output.progress_interval_s=0", "-o", under_file],
                 [regular], code=3)
    expect_error("cli_output_is_regular_file",
                 ["run", poiseuille, "-s", "time.end_s=0.002", "-s", "output.progress_interval_s=0", "-o", regular],
                 [regular], code=3)

    # --- earlier outputs are never lost without --overwrite ---------------------------------
    quick = ["-s", "time.end_s=0.002", "-s", "output.progress_interval_s=0", "-s", "output.snapshot_interval_s=0.001"]
    kept = os.path.join(WORK, "kept_run")
    r = surge("run", poiseuille, *quick, "-o", kept)
    with open(os.path.join(kept, "params.ini")) as f:
        params_before = f.read()
    snaps_before = sorted(f for f in os.listdir(kept) if f.startswith("snap_"))
    report("outputs_first_run", exited(r, 0) and len(snaps_before) >= 3, r)
    expect_error("outputs_rerun_refused", ["run", poiseuille, *quick, "-s", "fluid.viscosity_m2ps=0.02", "-o", kept],
                 [kept, "earlier run", "--overwrite", "nothing was written"])
    with open(os.path.join(kept, "params.ini")) as f:
        report("outputs_rerun_left_the_run_alone", f.read() == params_before and
               sorted(f for f in os.listdir(kept) if f.startswith("snap_")) == snaps_before, None,
               "params.ini or the snapshots changed")
    user_file = write_file(os.path.join("kept_run", "notes.txt"), "mine\n")
    r = surge("run", poiseuille, "-s", "time.end_s=0.001", *quick[2:], "-o", kept, "--overwrite")
    snaps_after = sorted(f for f in os.listdir(kept) if f.startswith("snap_"))
    report("outputs_overwrite_replaces_the_run_only", exited(r, 0) and "--overwrite: removed" in r.stderr and
           len(snaps_after) < len(snaps_before) and os.path.isfile(user_file), r,
           "snapshots %s -> %s; notes.txt %s" % (snaps_before, snaps_after, os.path.isfile(user_file)))
    # without -o: a fresh runs/<case>-N
    home = os.path.join(WORK, "cwd_default")
    os.makedirs(home, exist_ok=True)
    r1 = surge("run", poiseuille, *quick, cwd=home)
    r2 = surge("run", poiseuille, *quick, cwd=home)
    report("outputs_default_folder_fresh_name", exited(r1, 0) and exited(r2, 0) and
           os.path.isfile(os.path.join(home, "runs", "poiseuille", "params.ini")) and
           os.path.isfile(os.path.join(home, "runs", "poiseuille-2", "params.ini")) and "poiseuille-2" in r2.stderr,
           r2)
    # frames: stale frames of another run are refused, and cleared by --overwrite
    frames = os.path.join(WORK, "kept_frames")
    os.makedirs(frames, exist_ok=True)
    stale = write_file(os.path.join("kept_frames", "frame_000099.png"), b"old")
    expect_error("outputs_frames_refused", ["run", poiseuille, *quick, "-o", os.path.join(WORK, "fr_run"), "--frames",
                                            frames], [frames, "frames", "--overwrite"])
    report("outputs_frames_left_alone", os.path.isfile(stale), None, "frame_000099.png was removed")
    expect_error("outputs_movie_folder_checked_first",
                 ["run", poiseuille, *quick, "-o", os.path.join(WORK, "mv_run"), "--movie",
                  os.path.join(WORK, "no_such_folder", "m.mp4")], ["no_such_folder", "does not exist"])
    report("outputs_movie_folder_nothing_run", not os.path.exists(os.path.join(WORK, "mv_run", "params.ini")), None,
           "the run started before the movie's folder was checked")

    # --- resolution and cost in surge check --------------------------------------------------
    r = surge("check", os.path.join(cases_dir, "belt_front.ini"), "-s", "numerics.dp_m=0.004")
    report("check_warns_few_particles_in_depth", exited(r, 0) and "4.5 particles" in r.stdout and
           "dp <= 0.0012 m gives 15" in r.stdout and "estimated memory" in r.stdout and
           "wall time per simulated second" in r.stdout, r)
    # the wall-time estimate counts the wall particles with the fluid's: the debris surge with 60 discs has about as
    # many of each, and a step costs about the same per wall particle (docs/performance.md)
    r = surge("check", os.path.join(cases_dir, "debris_surge.ini"), "-s", "numerics.dp_m=0.04", "-s",
              "boulders.placement=graded", "-s", "boulders.count=60", "-s", "boulders.seed=1")
    counts = re.search(r"ok: (\d+) fluid \+ (\d+) wall particles", r.stdout)
    cost = re.search(r"\((\d+) list entries per fluid particle\); at most ([0-9.e+]+) steps .* about ([0-9.e+]+) s of "
                     r"wall time per simulated second on 2 cores, wall particles counted as fluid ones", r.stdout)
    if counts and cost:
        fluid, walls = int(counts.group(1)), int(counts.group(2))
        entries, steps, estimate = int(cost.group(1)), float(cost.group(2)), float(cost.group(3))
        expected = (fluid + walls) * steps * (1.37e-7 + 4.43e-9 * entries)
    report("check_estimate_counts_walls", exited(r, 0) and counts is not None and cost is not None and
           walls > 0.5 * fluid and abs(estimate / expected - 1) < 0.02, None,
           "estimate %s s against (fluid + walls) x steps x cost %s s:\n%s" % (
               cost.group(3) if cost else "?", "%.3g" % expected if counts and cost else "?", r.stdout + r.stderr))
    r = surge("check", os.path.join(cases_dir, "boulder_settling.ini"), "-s", "numerics.dp_m=0.005")
    report("check_warns_coarse_discs", exited(r, 0) and "2.5 dp, fewer than 4" in r.stdout, r)
    # c0's viscous term for discs (Morris et al. 1997): the loaded channel at its derived c0 gets 10 x sqrt(nu u / r) =
    # 10 x sqrt(0.467 x 0.07709 / 0.02) = 13.42 m/s, where its speed alone gives 0.77 m/s; without discs the term is
    # absent; the debris surge's discs keep the fall term's 112 m/s
    loaded = os.path.join(cases_dir, "poiseuille_loaded.ini")
    r = surge("check", loaded, "-s", "numerics.c0_mps=0", "-s", "numerics.dp_m=0.01")
    c0 = re.search(r"c0 = ([0-9.]+) m/s \(([^;]*);", r.stdout)
    report("check_c0_discs_viscous_term", exited(r, 0) and c0 is not None and abs(float(c0.group(1)) / 13.416 - 1) < 1e-3
           and c0.group(2) == "set by the discs' viscous pressures" and "r = 0.02 m the smallest radius" in r.stdout, r)
    r = surge("check", loaded, "-s", "numerics.c0_mps=0", "-s", "numerics.dp_m=0.01", "-s", "boulders.placement=none")
    c0 = re.search(r"c0 = ([0-9.]+) m/s \(([^;]*);", r.stdout)
    report("check_c0_no_discs_no_viscous_term", exited(r, 0) and c0 is not None and
           abs(float(c0.group(1)) / 0.7709 - 1) < 1e-3 and "viscous speed" not in r.stdout, r)
    r = surge("check", os.path.join(cases_dir, "debris_surge.ini"), "-s", "numerics.dp_m=0.04", "-s",
              "boulders.placement=graded", "-s", "boulders.count=60", "-s", "boulders.density_ratio=0.9")
    c0 = re.search(r"c0 = ([0-9.]+) m/s \(([^;]*);", r.stdout)
    report("check_c0_debris_discs_fall_term", exited(r, 0) and c0 is not None and abs(float(c0.group(1)) / 112.214 - 1) <
           1e-4 and c0.group(2) == "set by the speed", r)
    # the implicit scheme with discs under 2.5 dp in radius (the debris surge stopped at 1.5 dp), and not at 2.5 dp
    r = surge("check", os.path.join(cases_dir, "boulder_settling.ini"), "-s", "numerics.dp_m=0.007", "-s",
              "numerics.scheme=implicit")
    r_fine = surge("check", os.path.join(cases_dir, "boulder_settling.ini"), "-s", "numerics.dp_m=0.005", "-s",
                   "numerics.scheme=implicit")
    report("check_warns_implicit_coarse_discs", exited(r, 0) and exited(r_fine, 0) and
           "implicit scheme with discs under 2.5 dp in radius (the smallest here is 1.8 dp)" in r.stdout and
           "dp <= 0.005 m gives 2.5" in r.stdout and "implicit scheme with discs" not in r_fine.stdout, r)
    # the implicit scheme at a fixed step shorter than its own at rest: with the kernels cut off under the free
    # surface the still tank's surface does not hold; with its mirror images (the default) it does, and no warning
    r = surge("check", os.path.join(cases_dir, "still_tank.ini"), "-s", "numerics.scheme=implicit", "-s",
              "numerics.dt_fixed_s=0.005", "-s", "implicit.surface_images=0")
    report("check_warns_implicit_short_fixed_step", exited(r, 0) and "dt_fixed_s = 0.005 s is shorter" in r.stdout and
           "(0.0204 s" in r.stdout and "nu dt / dp^2 = 0.05 here" in r.stdout, r)
    r = surge("check", os.path.join(cases_dir, "still_tank.ini"), "-s", "numerics.scheme=implicit", "-s",
              "numerics.dt_fixed_s=0.001")
    report("check_quiet_implicit_short_fixed_step_images", exited(r, 0) and "warning" not in r.stdout + r.stderr, r)
    r = surge("check", os.path.join(cases_dir, "still_tank.ini"), "-s", "numerics.scheme=implicit", "-s",
              "numerics.dt_fixed_s=0.03")
    report("check_quiet_implicit_long_fixed_step", exited(r, 0) and "warning" not in r.stdout + r.stderr, r)
    r = surge("check", os.path.join(cases_dir, "still_tank.ini"), "-s", "numerics.scheme=implicit", "-s",
              "implicit.cfl=0.1", "-s", "implicit.surface_images=0")
    report("check_warns_implicit_low_cfl", exited(r, 0) and "implicit.cfl = 0.1 is below its default 0.25" in r.stdout,
           r)
    r = surge("check", os.path.join(cases_dir, "still_tank.ini"))
    report("check_quiet_when_resolved", exited(r, 0) and "warning" not in r.stdout + r.stderr and
           "note" not in r.stdout + r.stderr, r)

    # --- who may steer a run: a control socket other machines can reach is refused, any transport
    for n, endpoint in enumerate(("tcp://0.0.0.0:5999", "tcp://*:5999", "norm://127.0.0.1:5999",
                                  "epgm://eth0;239.192.1.1:5999")):
        expect_error("cli_control_not_local_%d_%s" % (n, endpoint.split(":")[0]),
                     ["run", tank_case, "-o", out, "--control", endpoint], [endpoint, "refused"])
    r = surge("run", tank_case, "-s", "time.end_s=0.001", "-o", os.path.join(WORK, "pub_norm"), "--publish",
              "tcp://0.0.0.0:0")
    report("cli_publish_not_local_warns", "not bound to loopback" in r.stderr, r)

    # --- messages ----------------------------------------------------------------------------------------
    empty = write_file("empty.ini", "# nothing but a comment\n\n")
    expect_error("case_empty_refused", ["check", empty], [empty, "no parameters"])
    expect_error("cli_s_did_you_mean", ["run", tank_case, "-o", out, "-s", "dp_m=0.001"],
                 ["dp_m", "did you mean numerics.dp_m"])
    expect_error("cli_s_long_key_not_truncated", ["run", tank_case, "-o", out, "-s",
                                                  "numerics.dp_m" + "x" * 300 + "=0.001"], ["unknown parameter"])

    # --- the shipped cases, the parameter reference, help -----------------------------------------------
    shipped = sorted(f for f in os.listdir(cases_dir) if f.endswith(".ini"))
    report("shipped_cases_found", len(shipped) > 0, None, "no cases/*.ini in %s" % cases_dir)
    for name in shipped:
        r = surge("check", os.path.join(cases_dir, name))
        report("check_shipped_%s" % name[:-4], exited(r, 0) and "ok" in r.stdout, r)
        # changing dp alone never breaks a shipped scene: half and twice its spacing run, except that discs drawn
        # from a grading curve need 3 dp across the smallest, which a coarser dp is refused for, naming the dp
        with open(os.path.join(cases_dir, name)) as f:
            text = f.read()
        found = re.search(r"^\s*dp_m\s*=\s*([0-9.eE+-]+)", text, re.M)
        graded = re.search(r"^\s*placement\s*=\s*graded", text, re.M) is not None
        dp = float(found.group(1)) if found else None
        for factor in (0.5, 2.0):
            if dp is None:
                break
            r = surge("check", os.path.join(cases_dir, name), "-s", "numerics.dp_m=%.17g" % (dp * factor))
            refused_by_name = graded and factor > 1 and exited(r, 2) and "numerics.dp_m <=" in r.stderr
            report("check_shipped_%s_dp_x%g" % (name[:-4], factor),
                   (exited(r, 0) and "ok" in r.stdout) or refused_by_name, r)

    r = surge("params")
    ok = exited(r, 0)
    documented, section = set(), None
    for line in r.stdout.splitlines():
        m = re.match(r"^##\s*\[(\w+)\]", line)
        if m:
            section = m.group(1)
        m = re.match(r"^\|\s*`([^`]+)`\s*\|", line)
        if m and section:
            documented.add((section, m.group(1)))
    report("params_exit_0", ok and len(documented) > 0, r)
    undocumented = []
    for name in shipped:
        for sec, key in parse_case(os.path.join(cases_dir, name)):
            if (sec, key) not in documented:
                undocumented.append("%s:[%s]%s" % (name, sec, key))
    report("params_lists_every_case_key", ok and not undocumented, r if not ok else None,
           "not in 'surge params': " + ", ".join(sorted(set(undocumented))))

    for args in (["--help"], ["-h"], ["run", "--help"], ["check", "--help"], ["params", "--help"],
                 ["version", "--help"]):
        r = surge(*args)
        report("help_" + "_".join(a.strip("-") for a in args),
               exited(r, 0) and "usage" in r.stdout.lower(), r)
    # help text of run documents the restart and thread options
    r = surge("run", "--help")
    miss = missing_text(r.stdout, ["--restart", "--threads", "-o", "-s"])
    report("help_run_lists_options", exited(r, 0) and not miss, r, "missing %s" % miss if miss else None)


# ---------------------------------------------------------------------------------------------------------
# GROUP blowup


def checkpoint_position(path):
    """(step, time_s) of a checkpoint: after the 24-byte header and the parameter text."""
    with open(path, "rb") as f:
        head = f.read(24)
        f.seek(24 + struct.unpack("<Q", head[16:24])[0])
        return struct.unpack("<qd", f.read(16))


def read_csv_rows(path):
    with open(path) as f:
        lines = [l.rstrip("\n") for l in f if l.strip()]
    return lines[0].split(","), [l.split(",") for l in lines[1:]]


def group_blowup():
    from surgepy import vtp

    case = os.path.join(SOURCE, "cases", "still_tank.ini")
    out = os.path.join(WORK, "blowup")
    r = surge("run", case, "-s", "numerics.dt_fixed_s=0.01", "-s", "output.progress_interval_s=0", "-o", out,
              timeout=RUN_TIMEOUT_S)
    problems = []
    if r.timed_out:
        problems.append("did not stop within %d s" % RUN_TIMEOUT_S)
    elif r.rc != 1:
        problems.append("exit code %d, expected 1" % r.rc)
    report("blowup_exit_1", not problems, r, "; ".join(problems))
    check_names = ["non-finite value", "density far from rho0", "particle left the domain",
                   "particle crossed a wall", "time step collapsed"]
    named = [c for c in check_names if c in r.stderr]
    report("blowup_message_names_check", bool(named), r, "stderr names none of %s" % check_names)
    miss = missing_text(r.stderr, ["health check failed", "particle", "step", "t ="])
    report("blowup_message_details", not miss, r, "stderr lacks %s" % miss)
    m = re.search(r"health check failed: .* at particle (-?\d+), step (\d+), t = ([0-9.eE+-]+) s", r.stderr)
    report("blowup_message_format", m is not None and int(m.group(1)) >= 0, r,
           "no 'health check failed: CHECK at particle N, step S, t = T s' with a particle id")
    fail_step = int(m.group(2)) if m else None
    fail_t = float(m.group(3)) if m else None
    report("blowup_message_names_outputs", "last_good.vtp" in r.stderr and "last_good.bin" in r.stderr, r)

    for name in ("last_good.vtp", "last_good.bin", "params.ini", "diagnostics.csv"):
        report("blowup_writes_%s" % name.replace(".", "_"), os.path.isfile(os.path.join(out, name)), r,
               "%s missing in %s (has: %s)" % (name, out, sorted(os.listdir(out)) if os.path.isdir(out) else "no folder"))

    path = os.path.join(out, "last_good.vtp")
    if os.path.isfile(path):
        try:
            d = vtp.read_vtp(path)
            err = None
        except Exception as e:  # noqa: BLE001 - any reader error is a failed check
            d, err = None, "%s: %s" % (type(e).__name__, e)
        report("blowup_last_good_readable", d is not None, None, err)
        if d is not None:
            bad = [k for k in ("points", "velocity_mps", "density_kgpm3")
                   if k not in d or not np.all(np.isfinite(np.asarray(d[k], dtype=float)))]
            report("blowup_last_good_finite", not bad and len(d["points"]) > 0, None,
                   "non-finite or missing: %s" % bad)
            step, t = d.get("step"), d.get("time_s")
            report("blowup_last_good_before_failure",
                   fail_step is not None and step is not None and step < fail_step and t < fail_t + 1e-12, None,
                   "last_good step %s t %s, failure at step %s t %s" % (step, t, fail_step, fail_t))
            # the last good state passed the monitor: fluid densities within 1 +- max_density_deviation (0.1)
            fluid = np.asarray(d.get("kind", [])) == 0
            rho = np.asarray(d.get("density_kgpm3", []), dtype=float)
            dev = float(np.max(np.abs(rho[fluid] / 1000.0 - 1.0))) if fluid.any() else math.inf
            report("blowup_last_good_is_healthy", dev <= 0.1 + 1e-6, None,
                   "max |rho/rho0 - 1| of the fluid in last_good.vtp is %g > 0.1" % dev)

    path = os.path.join(out, "last_good.bin")
    if os.path.isfile(path):
        with open(path, "rb") as f:
            magic = f.read(8)
        report("blowup_checkpoint_is_checkpoint", magic == b"SURGECK1", None, "starts with %r" % magic)
        step = checkpoint_position(path)[0] if magic == b"SURGECK1" else None
        report("blowup_checkpoint_is_last_good", fail_step is not None and step == fail_step - 1, None,
               "last_good.bin at step %s, the failure at step %s" % (step, fail_step))

    path = os.path.join(out, "diagnostics.csv")
    if os.path.isfile(path):
        with open(path) as f:
            text = f.read()
        header, rows = read_csv_rows(path)
        bad_words = [w for w in ("nan", "inf") if w in text.lower()]
        values_ok = True
        try:
            vals = [float(x) for row in rows for x in row]
            values_ok = all(math.isfinite(v) for v in vals) and all(len(row) == len(header) for row in rows)
        except ValueError:
            values_ok = False
        report("blowup_diagnostics_clean", not bad_words and values_ok and len(rows) >= 1, None,
               "diagnostics.csv: %s, %d rows, parse ok %s" % (bad_words, len(rows), values_ok))

    path = os.path.join(out, "params.ini")
    if os.path.isfile(path):
        with open(path) as f:
            text = f.read()
        report("blowup_params_has_fixed_dt", re.search(r"^dt_fixed_s\s*=\s*0\.01\s*$", text, re.M) is not None,
               None, "params.ini does not record dt_fixed_s = 0.01")
        r2 = surge("check", path)
        report("blowup_params_reloads_as_case", exited(r2, 0) and "ok" in r2.stdout, r2)

    # a periodic checkpoint written before the stop stays (an earlier state to rerun the approach from)
    out = os.path.join(WORK, "blowup_periodic")
    r = surge("run", case, "-s", "numerics.dt_fixed_s=0.004", "-s", "output.checkpoint_interval_s=0.008",
              "-s", "output.progress_interval_s=0", "-o", out, timeout=RUN_TIMEOUT_S)
    m = re.search(r"health check failed: .* step (\d+),", r.stderr)
    periodic, last_good = os.path.join(out, "checkpoint.bin"), os.path.join(out, "last_good.bin")
    steps = [checkpoint_position(p)[0] if os.path.isfile(p) else None for p in (periodic, last_good)]
    report("blowup_keeps_periodic_checkpoint",
           exited(r, 1) and m is not None and steps[1] == int(m.group(1)) - 1 and steps[0] is not None and
           0 < steps[0] < steps[1] and "checkpoint.bin keeps the last periodic checkpoint" in r.stderr, r,
           "checkpoint.bin at step %s, last_good.bin at step %s" % tuple(steps))

    r = surge("run", case, "-s", "time.end_s=0.05", "-s", "output.progress_interval_s=0",
              "-o", os.path.join(WORK, "healthy"), timeout=RUN_TIMEOUT_S)
    report("healthy_short_run_exit_0", exited(r, 0) and state_hash(r) is not None, r)
    report("healthy_short_run_no_last_good", not os.path.exists(os.path.join(WORK, "healthy", "last_good.vtp")), None,
           "a healthy run wrote last_good.vtp")


# ---------------------------------------------------------------------------------------------------------
# GROUP restart


def group_restart():
    from surgepy import vtp

    case = os.path.join(SOURCE, "cases", "belt_front.ini")
    quiet = ["-s", "output.progress_interval_s=0"]
    dir_a, dir_b = os.path.join(WORK, "A"), os.path.join(WORK, "B")

    ra = surge("run", case, "-s", "time.end_s=0.04", *quiet, "-o", dir_a, timeout=RUN_TIMEOUT_S)
    hash_a = state_hash(ra)
    report("uninterrupted_run", exited(ra, 0) and hash_a is not None, ra, "needs exit 0 and a final 'state hash'")
    rb = surge("run", case, "-s", "time.end_s=0.02", *quiet, "-o", dir_b, timeout=RUN_TIMEOUT_S)
    report("first_half_run", exited(rb, 0) and state_hash(rb) is not None, rb)
    rc = surge("run", "--restart", os.path.join(dir_b, "checkpoint.bin"), "-s", "time.end_s=0.04",
               timeout=RUN_TIMEOUT_S)
    hash_c = state_hash(rc)
    report("restarted_run", exited(rc, 0) and hash_c is not None, rc, "needs exit 0 and a final 'state hash'")
    report("restart_hash_equals_uninterrupted", hash_a is not None and hash_a == hash_c, rc,
           "uninterrupted %s, restarted %s" % (hash_a, hash_c))
    report("restart_outputs_to_checkpoint_folder", dir_b in rc.stderr, rc, "stderr does not name %s" % dir_b)

    pvd = os.path.join(dir_b, "run.pvd")
    try:
        entries = vtp.read_pvd(pvd)
        err = None
    except Exception as e:  # noqa: BLE001
        entries, err = [], "%s: %s" % (type(e).__name__, e)
    times = [t for t, _ in entries]
    increasing = all(b > a for a, b in zip(times, times[1:]))
    report("restart_pvd_increasing", err is None and len(times) >= 3 and increasing, None,
           err or "times %s" % times)
    covers = bool(times) and times[0] == 0.0 and any(0 < t < 0.04 for t in times) and times[-1] >= 0.04
    report("restart_pvd_covers_both_halves", covers, None, "times %s" % times)
    missing = [f for _, f in entries if not os.path.isfile(os.path.join(dir_b, f))]
    report("restart_pvd_files_exist", not missing, None, "listed but missing: %s" % missing)

    # the final snapshots of both runs hold the same particles
    try:
        last_a = vtp.read_vtp(os.path.join(dir_a, vtp.read_pvd(os.path.join(dir_a, "run.pvd"))[-1][1]))
        last_b = vtp.read_vtp(os.path.join(dir_b, entries[-1][1]))
        same = all(np.array_equal(last_a[k], last_b[k]) for k in ("points", "velocity_mps", "density_kgpm3", "id"))
        err = None if same else "final snapshots differ"
    except Exception as e:  # noqa: BLE001
        same, err = False, "%s: %s" % (type(e).__name__, e)
    report("restart_final_snapshot_equals_uninterrupted", same, None, err)

    try:
        header, rows_b = read_csv_rows(os.path.join(dir_b, "diagnostics.csv"))
        _, rows_a = read_csv_rows(os.path.join(dir_a, "diagnostics.csv"))
        tb = [float(row[0]) for row in rows_b]
        err = None
    except Exception as e:  # noqa: BLE001
        rows_a, rows_b, tb, err = [], [], [], "%s: %s" % (type(e).__name__, e)
    report("restart_diagnostics_both_halves", err is None and any(t < 0.02 for t in tb) and any(t > 0.02 for t in tb),
           None, err or "times %s" % tb)
    report("restart_diagnostics_increasing", err is None and all(b > a for a, b in zip(tb, tb[1:])), None,
           err or "times %s (a repeated or out-of-order row)" % tb)
    report("restart_diagnostics_equal_uninterrupted", err is None and rows_a == rows_b, None,
           err or "uninterrupted rows %s\n    restarted rows %s" % (rows_a, rows_b))

    # the result does not depend on the thread count
    hashes = {}
    for n in (1, 2):
        r = surge("run", case, "-s", "time.end_s=0.04", *quiet, "-o", os.path.join(WORK, "T%d" % n),
                  "--threads", str(n), timeout=RUN_TIMEOUT_S)
        hashes[n] = state_hash(r)
        report("threads_%d_run" % n, exited(r, 0) and hashes[n] is not None and
               ("%d thread%s" % (n, "" if n == 1 else "s")) in r.stderr and "1 threads" not in r.stderr, r)
    report("threads_1_vs_2_same_hash", hashes[1] is not None and hashes[1] == hashes[2], None,
           "--threads 1: %s, --threads 2: %s" % (hashes[1], hashes[2]))
    report("threads_1_equals_default_run", hashes[1] is not None and hashes[1] == hash_a, None,
           "--threads 1: %s, default threads: %s" % (hashes[1], hash_a))

    # Ctrl-C stops a long run at the next step with a checkpoint (exit 4), and the run continues from it
    dir_i = os.path.join(WORK, "I")
    argv = [SURGE, "run", case, "-s", "time.end_s=100", *quiet, "-o", dir_i, "--threads", "1"]
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            cwd=WORK, env=ENV)
    csv_path = os.path.join(dir_i, "diagnostics.csv")
    deadline = time.time() + RUN_TIMEOUT_S
    while time.time() < deadline and proc.poll() is None and \
            (not os.path.isfile(csv_path) or os.path.getsize(csv_path) < 2000):
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    try:
        _, err_bytes = proc.communicate(timeout=RUN_TIMEOUT_S)
        rc_i, timed_out = proc.returncode, False
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err_bytes = proc.communicate()
        rc_i, timed_out = None, True
    r_int = Result(argv, rc_i, "", err_bytes.decode("utf-8", "replace"), timed_out)
    checkpoint = os.path.join(dir_i, "checkpoint.bin")
    report("sigint_stops_with_checkpoint", exited(r_int, 4) and "interrupted" in r_int.stderr and
           os.path.isfile(checkpoint), r_int, "needs exit 4, 'interrupted' and checkpoint.bin")
    report("sigint_says_how_to_continue", "--restart " + checkpoint in r_int.stderr, r_int,
           "needs the --restart command")

    # OpenMP threads wait passively unless the user set how they wait (a policy or a spin count): the running
    # process's environment
    for given, wanted in ((None, ["OMP_WAIT_POLICY=PASSIVE"]), ("OMP_WAIT_POLICY=ACTIVE", ["OMP_WAIT_POLICY=ACTIVE"]),
                          ("GOMP_SPINCOUNT=1000", ["GOMP_SPINCOUNT=1000"])):
        env = {k: v for k, v in ENV.items() if k not in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")}
        if given:
            key, _, value = given.partition("=")
            env[key] = value
        name = "default" if given is None else "user_" + given.split("=")[0].lower()
        proc = subprocess.Popen([SURGE, "run", case, "-s", "time.end_s=100", *quiet, "-o",
                                 os.path.join(WORK, "wait_%s" % name), "--threads", "1"], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        seen, deadline = None, time.time() + 30
        while time.time() < deadline and proc.poll() is None and seen is None:
            time.sleep(0.2)
            try:
                with open("/proc/%d/environ" % proc.pid, "rb") as f:
                    entries = f.read().split(b"\0")
                if os.path.isfile(os.path.join(WORK, "wait_%s" % name, "params.ini")):
                    seen = sorted(e.decode() for e in entries
                                  if e.startswith(b"OMP_WAIT_POLICY=") or e.startswith(b"GOMP_SPINCOUNT="))
            except OSError:
                pass
        proc.send_signal(signal.SIGINT)
        try:
            proc.communicate(timeout=RUN_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.communicate()
        report("omp_wait_%s" % name, seen == wanted, None, "the run's environment had %s" % seen)
    try:
        checkpoint_step, checkpoint_time_s = checkpoint_position(checkpoint)
    except (OSError, struct.error):
        checkpoint_step, checkpoint_time_s = None, 0.0
    r_cont = surge("run", "--restart", checkpoint, "-s", "time.end_s=%.9g" % (checkpoint_time_s + 0.005),
                   "-s", "output.diagnostics_interval_s=0", timeout=RUN_TIMEOUT_S)
    try:
        last_step = int(read_csv_rows(csv_path)[1][-1][1])
    except (OSError, ValueError, IndexError):
        last_step = None
    report("restart_after_sigint_continues", exited(r_cont, 0) and state_hash(r_cont) is not None and
           checkpoint_step is not None and last_step is not None and last_step > checkpoint_step, r_cont,
           "checkpoint step %s, last diagnostics step after the restart %s" % (checkpoint_step, last_step))

    # a restart into a new folder starts its diagnostics.csv with the header (from the continued run's checkpoint)
    dir_n = os.path.join(WORK, "N")
    shutil.rmtree(dir_n, ignore_errors=True)
    try:
        checkpoint_time_s = checkpoint_position(checkpoint)[1]
    except (OSError, struct.error):
        checkpoint_time_s = 0.0
    r_new = surge("run", "--restart", checkpoint, "-s", "time.end_s=%.9g" % (checkpoint_time_s + 0.003),
                  "-s", "output.diagnostics_interval_s=0.001", "-o", dir_n,
                  timeout=RUN_TIMEOUT_S)
    try:
        header_n, rows_n = read_csv_rows(os.path.join(dir_n, "diagnostics.csv"))
        err = None
    except Exception as e:  # noqa: BLE001
        header_n, rows_n, err = [], [], "%s: %s" % (type(e).__name__, e)
    report("restart_into_new_folder_csv_header", exited(r_new, 0) and header_n[:2] == ["time_s", "step"] and
           len(rows_n) > 0, r_new, err or "header %s, %d rows" % (header_n, len(rows_n)))

    # A run killed hard leaves only its last periodic checkpoint; the diagnostics rows it wrote after that
    # checkpoint are dropped on restart, so diagnostics.csv stays in step order without repeated steps
    dir_k = os.path.join(WORK, "K")
    shutil.rmtree(dir_k, ignore_errors=True)
    argv = [SURGE, "run", case, "-s", "time.end_s=100", *quiet, "-s", "output.checkpoint_interval_s=0.004",
            "-s", "output.diagnostics_interval_s=0", "-o", dir_k, "--threads", "1"]
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            cwd=WORK, env=ENV)
    checkpoint, csv_path = os.path.join(dir_k, "checkpoint.bin"), os.path.join(dir_k, "diagnostics.csv")
    # stop the run (SIGSTOP) to look: kill it once diagnostics.csv has rows past the checkpoint on disk, else let
    # it go on and look again, so the case under test does not depend on when a fixed sleep ends
    deadline = time.time() + RUN_TIMEOUT_S
    checkpoint_step, killed_rows, killed_steps = -1, [], []
    err = "no checkpoint with diagnostics rows past it before the deadline"
    while time.time() < deadline and proc.poll() is None:
        if os.path.isfile(checkpoint):
            proc.send_signal(signal.SIGSTOP)
            try:
                checkpoint_step = checkpoint_position(checkpoint)[0]
                with open(csv_path) as f:
                    whole_rows = f.read().endswith("\n")  # else a row is half written: look again
                _, killed_rows = read_csv_rows(csv_path) if whole_rows else (None, [])
                killed_steps = [int(row[1]) for row in killed_rows]
            except (OSError, ValueError, IndexError, struct.error):
                killed_rows, killed_steps = [], []
            if killed_steps and max(killed_steps) > checkpoint_step:
                err = None
                break
            proc.send_signal(signal.SIGCONT)
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    report("hard_kill_left_rows_past_its_checkpoint", err is None and max(killed_steps) > checkpoint_step, None,
           err or "checkpoint step %d, last row step %d" % (checkpoint_step, max(killed_steps or [0])))
    end_s = float(killed_rows[-1][0]) + 0.002 if killed_rows else 0.01
    r_k = surge("run", "--restart", checkpoint, "-s", "time.end_s=%.6f" % end_s, timeout=RUN_TIMEOUT_S)
    try:
        _, rows = read_csv_rows(csv_path)
        steps = [int(row[1]) for row in rows]
    except (OSError, ValueError, IndexError):  # a missing, short or damaged table
        steps = []
    report("restart_after_hard_kill_drops_rows_past_the_checkpoint",
           exited(r_k, 0) and steps and all(b > a for a, b in zip(steps, steps[1:])) and steps[-1] > max(killed_steps or [0]),
           r_k, "steps around the checkpoint %d: %s" % (checkpoint_step,
                                                        [s for s in steps if abs(s - checkpoint_step) < 4]))

# GROUP default


def group_default():
    """The main job: surge run without a case runs the debris surge with boulders and renders it into its folder"""
    out = os.path.join(WORK, "demo")
    r = surge("run", "-o", out, "-s", "time.end_s=0.5", "-s", "output.progress_interval_s=0", "--threads", "2",
              timeout=RUN_TIMEOUT_S)
    report("default_run_finishes", exited(r, 0) and state_hash(r) is not None, r)
    frames = sorted(f for f in os.listdir(os.path.join(out, "frames"))) if os.path.isdir(os.path.join(out, "frames")) else []
    pngs = [f for f in frames if f.endswith(".png")]
    report("default_run_frames_every_0.1_s", len(pngs) == 6 and "frames.csv" in frames, None, str(frames))
    movie = os.path.join(out, "movie.mp4")
    report("default_run_movie", os.path.isfile(movie) and os.path.getsize(movie) > 1000, None,
           str(os.path.getsize(movie)) if os.path.isfile(movie) else "no movie.mp4")
    rows = []
    if os.path.isfile(os.path.join(out, "flow.csv")):
        with open(os.path.join(out, "flow.csv")) as f:
            rows = list(csv.DictReader(f))
    later = [r_ for r_ in rows if float(r_["time_s"]) > 0]
    report("default_run_flow_csv_froude_and_viscosity", len(rows) == 2 and later and all(
        math.isfinite(float(r_["froude"])) and float(r_["froude"]) > 0 and
        math.isfinite(float(r_["mu_eq_over_mu0"])) and float(r_["mu_eq_over_mu0"]) > 0 for r_ in later), None, str(rows))
    discs = 0
    if os.path.isfile(os.path.join(out, "boulders.csv")):
        with open(os.path.join(out, "boulders.csv")) as f:
            discs = len(f.read().strip().split("\n")) - 1
    report("default_run_discs", discs == 12, None, "%d discs in boulders.csv" % discs)
    report("default_run_says_where_the_movie_is", ("the movie is %s" % movie) in r.stderr and
           "flow.csv" in r.stderr, r)


def main():
    global SURGE, SOURCE, WORK
    if len(sys.argv) != 5 or sys.argv[4] not in ("inputs", "blowup", "restart", "default"):
        sys.stderr.write(__doc__)
        return 2
    SURGE = os.path.abspath(sys.argv[1])
    SOURCE = os.path.abspath(sys.argv[2])
    WORK = os.path.abspath(sys.argv[3])
    if os.path.isdir(WORK):
        shutil.rmtree(WORK)
    os.makedirs(WORK)
    {"inputs": group_inputs, "blowup": group_blowup, "restart": group_restart, "default": group_default}[sys.argv[4]]()
    if failures:
        print("%d check(s) FAILED: %s" % (len(failures), ", ".join(failures)))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
