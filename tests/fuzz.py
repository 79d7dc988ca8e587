#!/usr/bin/python3
"""A bounded, seeded fuzz pass over every outside input, against surge built with AddressSanitizer and
UndefinedBehaviorSanitizer (cmake -DSURGE_SANITIZE=ON; the fuzz_build test makes that build).

Usage: fuzz.py SURGE_SANITIZED SOURCE_DIR WORK_DIR GROUP [--count N] [--seed S]
  GROUP cases        mutated case files (every shipped case as seed) through `surge check`
  GROUP control      mutated and generated control requests against a live run: each gets a reply, or the run
                     ended by a request (stop, an end time) or by its health monitor, and is started again
  GROUP checkpoints  mutated checkpoints (a scene with and one without boulders) through `surge run --restart`;
                     most with the checksum recomputed, so the mutation reaches the reader behind it
  GROUP snapshots    mutated snapshots, run.pvd and params.ini of a run folder through `surge render`
  GROUP sizes        counts and sizes the files cannot hold (a snapshot's NumberOfPoints, a checkpoint's
                     parameter block, particle counts, contact count, and parameters describing a scene of 4e7
                     particles) and files that never end (a pipe, /dev/zero) in place of a snapshot collection, a
                     checkpoint and the boulders' CSV files: each refused with exit status 2 and a message naming
                     the file, what is wrong and, for a count, the file's size; refused before anything is built or
                     allocated for the count (each run under a 1 GB resident-memory limit)

An input fails when the program dies on a signal, a sanitizer reports (any "runtime error" or AddressSanitizer /
LeakSanitizer report; leaks inside libOSMesa are suppressed, tests/lsan.supp), it exits with a status outside the
classes its input may give (a case through surge check 0 or 2; a checkpoint 0, 1 or 2; a run folder through surge
render 0 or 2; a run a control request ended 0 or 1), refuses it without naming it, or does not finish within its
time limit. Control requests over 16 KiB, which ZeroMQ drops with their peer, go from a peer of their own, and the
run must then still answer a status. A failing
input is kept in WORK_DIR/failures/ with the seed and the command, to rerun by hand. Longer runs outside CI:
a larger --count, another --seed, or a coverage-guided engine (docs/verification.md, "Fuzzing").
"""
import json
import os
import random
import re
import shutil
import struct
import subprocess
import sys

from surgepy import client as surge_client

SURGE, SOURCE, WORK, GROUP = sys.argv[1:5]
OPTIONS = dict(zip(sys.argv[5::2], sys.argv[6::2]))
SEED = int(OPTIONS.get("--seed", 1))
DEFAULT_COUNT = {"cases": 1200, "control": 2000, "checkpoints": 300, "snapshots": 120, "sizes": 1}
COUNT = int(OPTIONS.get("--count", DEFAULT_COUNT[GROUP]))

ENV = dict(os.environ, OMP_WAIT_POLICY="PASSIVE", OMP_NUM_THREADS="1",
           ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:allocator_may_return_null=1",
           UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1",
           LSAN_OPTIONS="suppressions=" + os.path.join(SOURCE, "tests", "lsan.supp"))
SANITIZER_WORDS = re.compile(r"runtime error|AddressSanitizer|LeakSanitizer|UndefinedBehaviorSanitizer")
rng = random.Random(SEED)
failures = []


def verdict(rc, stderr, timed_out, allowed=(0, 1, 2, 3, 4), names=()):
    """None when surge behaved, else what went wrong: it finished, without a sanitizer report or a signal, with an
    exit status of the classes this input may give (allowed), and a refusal (2 bad input, 3 a file error) says
    "surge" and names the input (one of names, when given)."""
    if timed_out:
        return "did not finish within its time limit"
    if SANITIZER_WORDS.search(stderr):
        return "sanitizer report"
    if rc is None or rc < 0:
        return "killed by signal %s" % (-rc if rc else "?")
    if rc not in allowed:
        return "exit status %d is not one this input may give (%s)" % (rc, ", ".join(map(str, allowed)))
    if rc in (2, 3) and "surge" not in stderr:
        return "refused without a message"
    if rc in (2, 3) and names and not any(n in stderr for n in names):
        return "the refusal does not name the input (%s)" % " or ".join(names)
    return None


def record(kind, data, command, problem, stderr):
    folder = os.path.join(WORK, "failures")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "%s_%d_%d" % (GROUP, SEED, len(failures)))
    with open(path + ".input", "wb") as f:
        f.write(data)
    with open(path + ".txt", "w") as f:
        f.write("seed %d, %s\ncommand: %s\nproblem: %s\nstderr (end):\n%s\n" % (SEED, kind, command, problem,
                                                                              stderr[-6000:]))
    failures.append("%s: %s (input and stderr in %s.*)\n%s" % (kind, problem, path, stderr[-1500:]))


def run(args, timeout_s, env=ENV):
    try:
        p = subprocess.run(args, capture_output=True, env=env, timeout=timeout_s)
        return p.returncode, p.stderr.decode(errors="replace"), False
    except subprocess.TimeoutExpired as e:
        return None, (e.stderr or b"").decode(errors="replace"), True


def finish(what):
    print("%s: %d inputs, seed %d, %d failing" % (what, COUNT, SEED, len(failures)))
    for f in failures[:10]:
        print("FAILED " + f)
    sys.exit(1 if failures else 0)


# ---- byte-level mutations, shared by every group ----
SPECIAL_NUMBERS = [b"0", b"-1", b"-0", b"nan", b"NaN", b"inf", b"-inf", b"1e308", b"-1e308", b"1e-308", b"4.9e-324",
                   b"2147483648", b"9223372036854775808", b"-2147483649", b"0x10", b"1,5", b"1e", b"++1", b"", b"x",
                   b"1" * 400, b"0.5", b"2", b"1e-9", b"1e9"]


def mutate_bytes(data):
    data = bytearray(data)
    choice = rng.randrange(6)
    at = rng.randrange(len(data) + 1)
    if choice == 0 and data:
        data[min(at, len(data) - 1)] ^= 1 << rng.randrange(8)
    elif choice == 1:
        data[at:at] = bytes(rng.randrange(256) for _ in range(rng.randint(1, 8)))
    elif choice == 2:
        del data[at:at + rng.randint(1, 16)]
    elif choice == 3:
        data = data[:at]
    elif choice == 4:
        end = min(len(data), at + rng.randint(1, 64))
        data[at:at] = data[at:end] * rng.randint(1, 4)
    else:
        data[at:at] = rng.choice([b"\x00", b"\xff\xfe", b"\xe2\x82", b"\n", b"=", b"[", b"]", b"#", b"\\", b'"'])
    return bytes(data)


# ---- case files ----
NUMBER = re.compile(rb"(?<=[=\s])[-+]?[0-9.]+(?:e[-+]?[0-9]+)?")


def mutate_case(text):
    lines = text.split(b"\n")
    choice = rng.randrange(9)
    if choice == 0:
        numbers = list(NUMBER.finditer(text))
        if numbers:
            m = rng.choice(numbers)
            return text[:m.start()] + rng.choice(SPECIAL_NUMBERS) + text[m.end():]
    if choice == 1:  # a scale: length or count doubled or halved, never run away
        numbers = list(NUMBER.finditer(text))
        if numbers:
            m = rng.choice(numbers)
            try:
                value = float(m.group()) * rng.choice([0.5, 2.0])
                return text[:m.start()] + repr(value).encode() + text[m.end():]
            except ValueError:
                pass
    if choice == 2 and len(lines) > 1:
        del lines[rng.randrange(len(lines))]
    elif choice == 3:
        k = rng.randrange(len(lines))
        lines.insert(k, lines[k])
    elif choice == 4 and len(lines) > 1:
        a, b = rng.randrange(len(lines)), rng.randrange(len(lines))
        lines[a], lines[b] = lines[b], lines[a]
    elif choice == 5:
        k = rng.randrange(len(lines))
        lines[k] = lines[k].replace(b"]", b"", 1) if b"[" in lines[k] else lines[k].replace(b"_", b"", 1)
    elif choice == 6:
        k = rng.randrange(len(lines))
        lines[k] = lines[k] + b"x" * rng.choice([1, 300, 10000])
    elif choice == 7:
        lines.insert(rng.randrange(len(lines) + 1), rng.choice([b"[boulders]", b"[fluid]", b"[nope]", b"key = 1",
                                                                b"fluid.viscosity_m2ps = 0.1", b"=", b"[", b"count = 3"]))
    else:
        return mutate_bytes(text)
    return b"\n".join(lines)


def group_cases():
    seeds = sorted(os.path.join(SOURCE, "cases", f) for f in os.listdir(os.path.join(SOURCE, "cases"))
                   if f.endswith(".ini"))
    corpus = [open(f, "rb").read() for f in seeds]
    folder = os.path.join(WORK, "cases")
    os.makedirs(folder, exist_ok=True)
    path = os.path.join(folder, "input.ini")
    outcomes = {}
    for i in range(COUNT):
        data = rng.choice(corpus)
        for _ in range(rng.randint(1, 3)):
            data = mutate_case(data)
        with open(path, "wb") as f:
            f.write(data)
        rc, stderr, timed_out = run([SURGE, "check", path], 120)
        outcomes[rc] = outcomes.get(rc, 0) + 1
        problem = verdict(rc, stderr, timed_out, allowed=(0, 2), names=(path,))
        if problem:
            record("case file %d" % i, data, "surge check input.ini", problem, stderr)
    print("exit statuses: %s" % outcomes)
    finish("case files through surge check")


# ---- control requests ----
COMMANDS = ["list", "get", "set", "pause", "resume", "step", "snapshot", "checkpoint", "status"]


def random_value(depth=0):
    kind = rng.randrange(10 if depth < 3 else 7)
    if kind == 0:
        return rng.choice([0, 1, -1, 2 ** 31, -2 ** 31 - 1, 2 ** 53 + 1, 2 ** 63, 10 ** 30])
    if kind == 1:
        return rng.choice([0.0, -0.0, 1e-300, 1e300, -1e300, 0.5, 1e-9, 3.7, 89.9, 90.0, 360.0])
    if kind == 2:
        return rng.uniform(-10, 10)
    if kind == 3:
        return rng.choice(["", "none", "lind", "velocity", "x" * 5000, "\u0000", "\u20ac" * 50, "\ud800", " none",
                           "fluid.viscosity_m2ps", "1e3", "true"])
    if kind == 4:
        return rng.choice([True, False, None])
    if kind in (5, 6):
        return rng.uniform(0, 1e-2)
    if kind == 7:
        return [random_value(depth + 1) for _ in range(rng.randint(0, 3))]
    return {rng.choice(["cmd", "key", "value", "n", "x"]): random_value(depth + 1) for _ in range(rng.randint(0, 3))}


def plausible_value(param):
    """A value a user might set: the current one scaled, a bound, another choice, or the other boolean."""
    value = param.get("value")
    if isinstance(value, bool):
        return not value if rng.random() < 0.5 else value
    if isinstance(value, (int, float)):
        candidates = [value * rng.choice([0.5, 0.9, 1.1, 2.0]), param.get("min"), param.get("max")]
        return rng.choice([c for c in candidates if c is not None])
    return rng.choice(param.get("values") or [value])


def random_request(params):
    cmd = rng.choice(COMMANDS) if rng.random() < 0.9 else random_value()
    request = {"cmd": cmd} if rng.random() < 0.97 else {}
    if cmd in ("get", "set"):
        param = rng.choice(params)
        request["key"] = param["key"] if rng.random() < 0.9 else random_value()
        if cmd == "set":
            request["value"] = plausible_value(param) if rng.random() < 0.6 else random_value()
    if cmd == "step":
        request["n"] = rng.choice([1, 2, 5, 0, -1, 2.5, "3", 2 ** 40]) if rng.random() < 0.9 else random_value()
    if rng.random() < 0.1:
        request[rng.choice(["vlaue", "", "\u0000", "extra", "key", "n"])] = random_value()
    try:
        data = json.dumps(request, allow_nan=rng.random() < 0.05).encode("utf-8", "surrogatepass")
    except (ValueError, UnicodeEncodeError):
        data = b'{"cmd": "status"}'
    special = rng.random()
    if special < 0.3:
        for _ in range(rng.randint(1, 3)):
            data = mutate_bytes(data)
    elif special < 0.32:
        data = rng.choice([b"[" * 100000, b'{"cmd": ' * 20000, b'{"cmd": "status", "pad": "' + b"y" * 70000 + b'"}',
                           b'{"cmd": "get", "key": "' + b"a" * 60000 + b'"}', b"[" * 16000, b'{"cmd": ' * 2000,
                           b'{"cmd": "get", "key": "' + b"a" * 9000 + b'"}'])
    return data


MAX_REQUEST_BYTES = 16384  # ZeroMQ closes a peer that sends more (docs/protocol.md), without a reply


def send_oversize(live, data):
    """Sends a request over MAX_REQUEST_BYTES from a peer of its own (ZeroMQ drops that peer without a reply), then
    asks the run for its status on the usual socket: the run's reply (TimeoutError when it gives none)"""
    import zmq
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(live.endpoint)
    sock.send(data)
    answered = sock.poll(2000)
    sock.close()
    if answered:
        return {"ok": False, "error": "an oversize request was answered"}
    return live.control.request({"cmd": "status"})


class LiveRun:
    def __init__(self, index):
        self.dir = os.path.join(WORK, "control", "run%d" % index)
        shutil.rmtree(self.dir, ignore_errors=True)
        os.makedirs(self.dir)
        self.endpoint = "ipc://" + os.path.join(self.dir, "ctl.sock")
        self.stderr_path = os.path.join(self.dir, "stderr.txt")
        self.args = [SURGE, "run", os.path.join(SOURCE, "cases", "still_tank.ini"), "-o", os.path.join(self.dir, "out"),
                     "--threads", "1", "--control", self.endpoint, "--paused", "-s", "time.end_s=1000",
                     "-s", "output.snapshot_interval_s=0", "-s", "output.progress_interval_s=0",
                     "-s", "numerics.dp_m=0.01"]
        self.proc = subprocess.Popen(self.args, stderr=open(self.stderr_path, "w"), stdout=subprocess.DEVNULL,
                                     env=ENV)
        self.control = surge_client.Control(self.endpoint, 30)

    def stderr(self):
        with open(self.stderr_path, errors="replace") as f:
            return f.read()

    def end(self, timeout_s=60):
        try:
            return self.proc.wait(timeout_s), False
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return None, True


def ask_live(live, message):
    """The run's reply, or None where it ended (its health monitor) before it could answer"""
    try:
        return live.control.request(message) if live.proc.poll() is None else None
    except TimeoutError:
        return None


def group_control():
    runs, live = 0, LiveRun(0)
    params = live.control.request({"cmd": "list"})["params"]
    replies = {"ok": 0, "error": 0}
    for i in range(COUNT):
        data = random_request(params)
        try:
            reply = send_oversize(live, data) if len(data) > MAX_REQUEST_BYTES else live.control.request(data)
            replies["ok" if reply.get("ok") else "error"] += 1
            if not reply.get("ok") and not isinstance(reply.get("error"), str):
                record("request %d" % i, data, " ".join(live.args), "an error reply without its message", str(reply))
            continue
        except TimeoutError:
            pass
        except surge_client.ProtocolError as e:
            record("request %d" % i, data, " ".join(live.args), "reply is not a JSON object: %s" % e, live.stderr())
        if live.proc.poll() is None:  # no reply and still running: a hang
            live.end(1)
            record("request %d" % i, data, " ".join(live.args), "no reply within 30 s from a live run", live.stderr())
        else:
            rc, timed_out = live.end()
            problem = verdict(rc, live.stderr(), timed_out, allowed=(0, 1))
            if problem:
                record("request %d" % i, data, " ".join(live.args), "the run ended: " + problem, live.stderr())
        runs += 1
        live = LiveRun(runs)
    ctl_status, stopped = ask_live(live, {"cmd": "status"}) or {}, ask_live(live, {"cmd": "stop"})
    rc, timed_out = live.end()
    # the last requests may have set a health bound the running state breaks before the stop arrives: the monitor's
    # own stop (exit 1, its message) ends the run as cleanly
    by_monitor = rc == 1 and "health check failed" in live.stderr()
    problem = verdict(rc, live.stderr(), timed_out, allowed=(0, 1)) or (
        None if (rc == 0 and ctl_status.get("ok") and stopped and stopped.get("ok")) or by_monitor else
        "the last run did not stop cleanly (exit %s)" % rc)
    if problem:
        record("final stop", b"", " ".join(live.args), problem, live.stderr())
    print("replies: %s; the run was started again %d times (ended by a request or its health monitor)" %
          (replies, runs))
    finish("control requests against a live run")


# ---- checkpoints ----
def fnv1a(data):
    h = 0xcbf29ce484222325
    for byte in data:
        h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return h


def make_base_runs(kind):
    """Short runs whose checkpoint (or snapshots) seed the mutations: a fluid scene and a scene with boulders."""
    bases = []
    for name, case, extra in (("tank", "still_tank.ini", ["-s", "numerics.dp_m=0.01"]),
                              ("boulders", "boulder_settling.ini", [])):
        out = os.path.join(WORK, kind, "base_" + name)
        shutil.rmtree(out, ignore_errors=True)
        args = [SURGE, "run", os.path.join(SOURCE, "cases", case), "-o", out, "--threads", "1",
                "-s", "time.end_s=0.004", "-s", "output.snapshot_interval_s=0.002",
                "-s", "output.progress_interval_s=0"] + extra
        rc, stderr, timed_out = run(args, 300)
        if rc != 0:
            print("FAILED to make the base run %s: %s\n%s" % (name, " ".join(args), stderr[-3000:]))
            sys.exit(1)
        bases.append(out)
    return bases


def mutate_checkpoint(data):
    """A mutated checkpoint; usually with its closing FNV-1a checksum recomputed, so the reader sees the change."""
    body = data[:-8]
    choice = rng.randrange(4)
    if choice == 0:  # a value in the parameter block, with its length field kept right
        length = struct.unpack_from("<Q", body, 16)[0]
        text = body[24:24 + length]
        text = mutate_case(text)
        body = body[:16] + struct.pack("<Q", len(text)) + text + body[24 + length:]
    elif choice == 1:  # a field of the header or the state
        for _ in range(rng.randint(1, 4)):
            body = mutate_bytes(body)
    elif choice == 2:  # one 8-byte word set to a special value
        at = rng.randrange(0, max(1, len(body) - 8)) & ~7
        word = rng.choice([struct.pack("<d", v) for v in (0.0, -1.0, float("nan"), float("inf"), 1e300, 5e-324)] +
                          [struct.pack("<Q", v) for v in (0, 1 << 63, 0xFFFFFFFFFFFFFFFF, 1 << 32)])
        body = body[:at] + word + body[at + 8:]
    else:  # a 4-byte count or flag
        at = rng.randrange(0, max(1, len(body) - 4))
        body = body[:at] + struct.pack("<I", rng.choice([0, 1, 2, 0xFFFFFFFF, 1 << 31, 4, 5])) + body[at + 4:]
    if rng.random() < 0.8:
        return body + struct.pack("<Q", fnv1a(body))
    return body + data[-8:]


def group_checkpoints():
    bases = make_base_runs("checkpoints")
    corpus = [open(os.path.join(b, "checkpoint.bin"), "rb").read() for b in bases]
    folder = os.path.join(WORK, "checkpoints")
    path, out = os.path.join(folder, "input.bin"), os.path.join(folder, "restarted")
    outcomes = {}
    for i in range(COUNT):
        data = mutate_checkpoint(rng.choice(corpus))
        with open(path, "wb") as f:
            f.write(data)
        args = [SURGE, "run", "--restart", path, "-o", out, "--overwrite", "--threads", "1",
                "-s", "time.end_s=0.0045", "-s", "output.progress_interval_s=0"]
        rc, stderr, timed_out = run(args, 120)
        outcomes[rc] = outcomes.get(rc, 0) + 1
        problem = verdict(rc, stderr, timed_out, allowed=(0, 1, 2), names=(path,))
        if problem:
            record("checkpoint %d" % i, data, " ".join(args), problem, stderr)
    print("exit statuses: %s" % outcomes)
    finish("checkpoints through surge run --restart")


# ---- snapshots ----
def group_snapshots():
    bases = make_base_runs("snapshots")
    folder = os.path.join(WORK, "snapshots")
    target, frames = os.path.join(folder, "run"), os.path.join(folder, "frames")
    outcomes = {}
    for i in range(COUNT):
        base = rng.choice(bases)
        shutil.rmtree(target, ignore_errors=True)
        shutil.copytree(base, target)
        files = sorted(f for f in os.listdir(target) if f.endswith((".vtp", ".pvd")) or f == "params.ini")
        name = rng.choice(files)
        with open(os.path.join(target, name), "rb") as f:
            data = f.read()
        for _ in range(rng.randint(1, 4)):
            data = mutate_case(data) if name.endswith(".ini") or rng.random() < 0.3 else mutate_bytes(data)
        with open(os.path.join(target, name), "wb") as f:
            f.write(data)
        args = [SURGE, "render", target, "--frames", frames, "--overwrite"]
        rc, stderr, timed_out = run(args, 120)
        outcomes[rc] = outcomes.get(rc, 0) + 1
        problem = verdict(rc, stderr, timed_out, allowed=(0, 2), names=(target,))
        if problem:
            record("%s mutated (input %d)" % (name, i), data, " ".join(args), problem, stderr)
    print("exit statuses: %s" % outcomes)
    finish("snapshots, run.pvd and params.ini through surge render")


# ---- sizes read from files ----
# a count is refused before anything is built or allocated for it: a run that allocated for one of these counts
# first would pass this limit on its resident memory (AddressSanitizer then ends it with a report)
SIZES_ENV = dict(ENV, ASAN_OPTIONS=ENV["ASAN_OPTIONS"] + ":hard_rss_limit_mb=1000")


def expect_refusal(what, data, args, message):
    """The input must be refused as bad input (exit status 2) within 60 s, with a message matching `message`."""
    rc, stderr, timed_out = run(args, 60, SIZES_ENV)
    problem = verdict(rc, stderr, timed_out)
    if not problem and rc != 2:
        problem = "exit status %s, not 2 (bad input)" % rc
    if not problem and not re.search(message, stderr):
        problem = "the message does not match %r" % message
    print("%-62s %s" % (what, "ok" if not problem else "FAILED: " + problem))
    if problem:
        record(what, data, " ".join(args), problem, stderr)


def render_with(base, name, data, what, message):
    target = os.path.join(WORK, "sizes", "run")
    shutil.rmtree(target, ignore_errors=True)
    shutil.copytree(base, target)
    os.remove(os.path.join(target, name))
    if data is None:
        os.mkfifo(os.path.join(target, name))
    else:
        with open(os.path.join(target, name), "wb") as f:
            f.write(data)
    expect_refusal(what, data or b"", [SURGE, "render", target, "--frames", os.path.join(WORK, "sizes", "frames"),
                                       "--overwrite"], message)


def with_points(data, count):
    """A .vtp's bytes with its NumberOfPoints set to count"""
    return re.sub(rb'NumberOfPoints="[0-9]+"', b'NumberOfPoints="%d"' % count, data, count=1)


def appended_bytes(data):
    """The bytes of a .vtp's appended data (after its '_')"""
    return len(data) - data.index(b"_", data.index(b'<AppendedData encoding="raw">')) - 1


def with_checksum(body):
    """A checkpoint's bytes before its checksum, with the FNV-1a checksum that closes it"""
    return body + struct.pack("<Q", fnv1a(body))


def group_sizes():
    tank, boulders = make_base_runs("sizes")
    first = sorted(f for f in os.listdir(tank) if f.endswith(".vtp"))[0]
    body = sorted(f for f in os.listdir(boulders) if f.startswith("boulders_") and f.endswith(".vtp"))[0]
    # per snapshot kind: a count no file holds, and one its Points alone could hold (24 bytes a point) but not the
    # arrays read with them (49 bytes a particle, 72 a disc)
    for folder, name, what, huge_count, point_bytes in ((tank, first, "snapshot declaring", 2147483647, 49),
                                                        (boulders, body, "boulder snapshot declaring", 1000000000, 72)):
        vtp = open(os.path.join(folder, name), "rb").read()
        huge = with_points(vtp, huge_count)
        render_with(folder, name, huge, "%s %d points" % (what, huge_count),
                    r"%s: bad NumberOfPoints %d: the file holds %d bytes" % (re.escape(name), huge_count, len(huge)))
        thin_count = appended_bytes(vtp) // 30
        thin = with_points(vtp, thin_count)
        render_with(folder, name, thin, "%s more points than its arrays hold" % what,
                    r"%s: bad NumberOfPoints %d: the file holds %d bytes, too few for that many points \(%d bytes each"
                    % (re.escape(name), thin_count, len(thin), point_bytes))
    render_with(tank, "run.pvd", None, "run.pvd a pipe", r"run\.pvd' is not a regular file")

    checkpoint = open(os.path.join(tank, "checkpoint.bin"), "rb").read()
    path, out = os.path.join(WORK, "sizes", "input.bin"), os.path.join(WORK, "sizes", "restarted")
    restart = [SURGE, "run", "--restart", path, "-o", out, "--overwrite", "--threads", "1"]
    plen = struct.unpack_from("<Q", checkpoint, 16)[0]
    count, walls = struct.unpack_from("<ii", checkpoint, 24 + plen + 32)
    for what, at, value, message in (
            ("checkpoint parameter block of 2^40 bytes", 16, struct.pack("<Q", 1 << 40),
             r"bad parameter block length 1099511627776: the file holds %d bytes" % len(checkpoint)),
            ("checkpoint declaring 2^31-1 particles", 24 + plen + 32, struct.pack("<ii", 2147483647, 0),
             r"bad particle count 2147483647 \(walls 0\): the file holds %d bytes" % len(checkpoint)),
            ("checkpoint declaring more walls than particles", 24 + plen + 32, struct.pack("<ii", 10, 20),
             r"bad particle count 10 \(walls 20\)"),
            ("checkpoint declaring one fluid particle less than its scene", 24 + plen + 32,
             struct.pack("<ii", count - 1, walls),
             r"particle counts do not match the scene its parameters describe \(the checkpoint holds %d fluid and "
             r"%d wall particles, the scene %d and %d\)" % (count - walls - 1, walls, count - walls, walls))):
        data = with_checksum((checkpoint[:at] + value + checkpoint[at + len(value):])[:-8])
        with open(path, "wb") as f:
            f.write(data)
        expect_refusal(what, data, restart, re.escape("input.bin: ") + message)

    # parameters describing 4e7 fluid particles (dp 45 um in the 0.4 x 0.2 m block) in a checkpoint of 800: what
    # the file must hold for them is known before the scene is built
    text = checkpoint[24:24 + plen]
    small = re.sub(rb"(?m)^dp_m = .*$", b"dp_m = 4.5e-05", text, count=1)
    data = with_checksum(checkpoint[:16] + struct.pack("<Q", len(small)) + small + checkpoint[24 + plen:-8])
    with open(path, "wb") as f:
        f.write(data)
    expect_refusal("checkpoint whose parameters describe 4e7 particles", data, restart,
                   re.escape("input.bin: ") + r"its parameters describe a scene of 3\d{7} fluid particles \(and "
                   r"\d+ wall particles\): a checkpoint of it holds at least \d+ bytes; the file holds %d bytes"
                   % len(data))

    # the boulders' contact count (the contact solver's warm start) beyond what is left of the file
    bcheckpoint = open(os.path.join(boulders, "checkpoint.bin"), "rb").read()
    bplen = struct.unpack_from("<Q", bcheckpoint, 16)[0]
    real_bytes = struct.unpack_from("<I", bcheckpoint, 12)[0]
    bcount, bwalls = struct.unpack_from("<ii", bcheckpoint, 24 + bplen + 32)
    bvtp = open(os.path.join(boulders, body), "rb").read()
    discs = int(re.search(rb'NumberOfPoints="([0-9]+)"', bvtp).group(1))
    at = 24 + bplen + 40 + (bcount - bwalls) * (8 + 8 + 3 * real_bytes + 4) + 4 + (bcount - bwalls) * 16 + discs * 7 * 8
    contacts = struct.unpack_from("<i", bcheckpoint, at)[0]
    if not 0 <= contacts < 1000:
        print("FAILED: the boulder checkpoint's contact count is not where it was looked for (%d)" % contacts)
        failures.append("contact count not found")
    else:
        data = with_checksum((bcheckpoint[:at] + struct.pack("<i", 64 * discs + 1000) + bcheckpoint[at + 4:])[:-8])
        with open(path, "wb") as f:
            f.write(data)
        expect_refusal("checkpoint declaring more contacts than the file holds", data, restart,
                       re.escape("input.bin: ") + r"bad contact count %d: the file holds %d bytes, too few for that "
                       r"many contacts" % (64 * discs + 1000, len(data)))
    expect_refusal("/dev/zero as a checkpoint", b"", [SURGE, "run", "--restart", "/dev/zero", "-o", out,
                                                      "--overwrite"], r"'/dev/zero' is not a regular file")
    case = os.path.join(SOURCE, "cases", "boulder_settling.ini")
    for key in ("boulders.file", "boulders.grading_file"):
        extra = ["-s", "boulders.placement=" + ("graded" if key == "boulders.grading_file" else "file"),
                 "-s", "boulders.solid_fraction=0.1"]
        expect_refusal("%s = /dev/zero" % key, b"", [SURGE, "check", case, "-s", key + "=/dev/zero"] + extra,
                       r"%s: '/dev/zero' is not a regular file" % re.escape(key))
    finish("sizes and endless files")


os.makedirs(WORK, exist_ok=True)
{"cases": group_cases, "control": group_control, "checkpoints": group_checkpoints,
 "snapshots": group_snapshots, "sizes": group_sizes}[GROUP]()
