#!/usr/bin/python3
"""Live state and control of a running surge, through real pyzmq clients (docs/protocol.md).

Usage: test_stream.py SURGE_BINARY SOURCE_DIR WORK_DIR GROUP [SCHEME]
  SCHEME          explicit (the default) or implicit: every run takes -s numerics.scheme=SCHEME; the implicit
                  scheme with a fixed 1 ms step, so that the still tank's 0.15 s hold the steps the groups count,
                  and nu = 0.1 m^2/s (nu dt / dp^2 = 1: at the tank's own 0.001 the 1 ms step would be far below
                  the scheme's stable range, docs/validation/stability.md, "Short steps in a thin fluid").
  GROUP state     a subscriber's states (full and a field subset) match the same run's snapshots bit for bit;
                  headers follow the minimum contract; the bodies topic is well formed; stats end with "final".
  GROUP control   pause holds the step, step N runs N steps, a parameter set mid-run shows in the published
                  stats from its journaled step on (and not before), and replaying the journal reproduces the
                  steered run's state hash.
  GROUP inputs    every malformed control request gets its error reply and the run goes on to finish normally;
                  an oversize request or a vanished client does not disturb it; stop ends it with its outputs;
                  bad stream options and journals get clear errors.
  GROUP curve     surge keygen's files (modes, never replaced, read by pyzmq's zmq.auth); with --curve-key and
                  --curve-clients only an allowed client is answered and fed states, an unknown key or a plain
                  client gets nothing; a --control reachable from elsewhere is refused without keys and runs with
                  them; bad key files and option pairs get clear errors.
  GROUP peers     a burst of 400 connections at once (raw TCP that never greets, and ZeroMQ clients that greet
                  and then sit idle) against a run limited to 256 open files: the run keeps stepping and writes
                  every snapshot; its control socket still answers once the idle peers are closed.
  GROUP stalled   a subscriber that never reads (its subscription shown live first) does not hold the solver
                  back: the run finishes and states were dropped for it (step rates: tools/stream_bench.py).
  GROUP subsets   junk and many valid field-subset subscriptions from one peer (TCP on 127.0.0.1) do not keep a
                  state/x_m,y_m subscriber from its topic, then or after that peer left; subsets take turns, at
                  most 16 per state.
  GROUP endpoints --control and --publish on tcp://localhost:PORT, tcp://[::1]:*, tcp://127.0.0.1:* and a bare
                  port bind, and the log names the port bound; a request and a subscription through it are answered.
  GROUP replies   every control request gets exactly one reply, counted per client, under a flood: a DEALER client
                  sends 5000 requests and reads nothing for 3 s (its replies fill ZeroMQ's queue: the rest are
                  refused "busy", none dropped); 600 pipelined to a running run are all answered; another client
                  sends 2000 while a stop request ends the run (those still waiting are refused "the run has ended").
  GROUP ending    a client that never reads its replies, and one that keeps sending, cannot keep a run from exiting
                  once a stop ends it (the socket leaves the first after 1 s without reading, closes 5 s after
                  the end at most) and the run says what it left.
  GROUP strays    unsubscribe messages from raw ZeroMQ peers that never subscribed (and one that unsubscribes twice)
                  do not cancel other peers' subscriptions to state, stats and state/x_m,y_m; a genuine unsubscribe
                  by the last holder still releases its subset.

Each check prints "name: ok" or "name: FAILED ..."; the script exits 1 if any failed. Sockets are ipc:// files in
WORK_DIR, so tests running side by side never share a port (group subsets and endpoints bind TCP ports the system
picks). Every wait has a timeout: a hang is a failure.
"""
import itertools
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import sys
import threading
import time

import numpy as np
import zmq

SURGE, SOURCE, WORK = sys.argv[1], sys.argv[2], sys.argv[3]
from checks import check, finish  # noqa: E402
from surgepy import client as surge_client  # noqa: E402
from surgepy import vtp  # noqa: E402

TANK = os.path.join(SOURCE, "cases", "still_tank.ini")
SCHEME = (["-s", "numerics.scheme=" + sys.argv[5]] if len(sys.argv) > 5 else []) + \
    (["-s", "numerics.dt_fixed_s=0.001", "-s", "fluid.viscosity_m2ps=0.1"] if sys.argv[5:6] == ["implicit"] else [])



class Surge:
    """A surge run in the background with ipc:// publisher and control endpoints in its own folder."""

    def __init__(self, name, extra, publish=True, control=True, paused=False, case=TANK):
        self.dir = os.path.join(WORK, name)
        shutil.rmtree(self.dir, ignore_errors=True)
        os.makedirs(self.dir)
        self.out = os.path.join(self.dir, "out")
        self.pub = "ipc://" + os.path.join(self.dir, "pub.sock")
        self.ctl = "ipc://" + os.path.join(self.dir, "ctl.sock")
        self.args = [SURGE, "run", case, "-o", self.out, "--threads", "1", "-s", "output.progress_interval_s=0"]
        self.args += (["--publish", self.pub] if publish else []) + (["--control", self.ctl] if control else [])
        self.args += (["--paused"] if paused else []) + SCHEME + extra
        self.stderr_path = os.path.join(self.dir, "stderr.txt")
        env = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")
        self.proc = subprocess.Popen(self.args, stderr=open(self.stderr_path, "w"), stdout=subprocess.DEVNULL, env=env)

    def wait(self, timeout_s=120):
        try:
            self.rc = self.proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.rc = None
        with open(self.stderr_path) as f:
            self.stderr = f.read()
        return self.rc

    def describe(self):
        return "command: %s\nexit code: %s\nstderr: %s" % (" ".join(self.args), self.rc, self.stderr.strip())

    def state_hash(self):
        m = re.search(r"state hash ([0-9a-f]{16})", self.stderr)
        return m.group(1) if m else None


def wait_for(predicate, timeout_s, poll_s=0.02):
    deadline = time.time() + timeout_s
    while time.time() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(poll_s)
    return None


def collect_until_final(sub, run, quiet_s=10, limit_s=600):
    """Every message until the stats message with status "final"; [(topic, header, arrays)], found. Gives up once
    the run has exited and nothing has arrived for quiet_s (a starved client is slow, not stuck), or after
    limit_s whatever happens (a hang is a failure)."""
    messages, start, last_message = [], time.time(), time.time()
    while time.time() - start < limit_s:
        m = surge_client.receive(sub, 200)
        if m is None:
            if run.proc.poll() is not None and time.time() - last_message > quiet_s:
                break
            continue
        last_message = time.time()
        messages.append(m)
        if m[0] == "stats" and m[1]["status"] == "final":
            return messages, True
    return messages, False


# ---------------------------------------------------------------------------------------------------------------
def group_state():
    # every message kept: this group compares chosen steps (the first, the snapshots', the final stats) with the
    # run's own files, and a starved client that falls 4 messages behind would lose them (group stalled covers
    # the default queue's dropping)
    run = Surge("state", ["-s", "time.end_s=0.2", "-s", "output.snapshot_interval_s=0.05", "--publish-hz", "0",
                          "--publish-hwm", "1000000"], paused=True)
    ctx = zmq.Context.instance()
    subset_topic = "state/x_m,vx_mps"
    sub = surge_client.subscribe(run.pub, ["state", "bodies", "stats"], ctx, latest_only=False)
    sub.setsockopt(zmq.RCVHWM, 100000)
    ctl = surge_client.Control(run.ctl, 10)
    # while paused the publisher sends step 0 as soon as it sees a subscription: wait for it, then resume
    first = wait_for(lambda: surge_client.receive(sub, 100), 20)
    subset = surge_client.subscribe(run.pub, [subset_topic], ctx, latest_only=False)
    subset.setsockopt(zmq.RCVHWM, 100000)
    time.sleep(0.3)  # the subset subscription reaches the publisher thread
    reply = ctl.request({"cmd": "resume"})
    check("state: resume after the first state", first is not None and reply.get("ok"), str(reply))
    messages, finished = collect_until_final(sub, run)
    messages = ([first] if first else []) + messages
    subset_messages, _ = collect_until_final(subset, run, quiet_s=5) if finished else ([], False)
    rc = run.wait()
    check("state: run finishes with exit 0 and a final stats message", rc == 0 and finished, run.describe())

    states = {h["step"]: (h, a) for t, h, a in messages if t == "state"}
    bodies = [(h, a) for t, h, a in messages if t == "bodies"]
    stats = [h for t, h, a in messages if t == "stats"]
    check("state: many states received", len(states) >= 10, "%d states" % len(states))
    expected_fields = [("x_m", "f64"), ("y_m", "f64"), ("vx_mps", "f32"), ("vy_mps", "f32"),
                       ("density_kgpm3", "f32"), ("pressure_pa", "f32"), ("kind", "u8"), ("id", "i32")]
    bad = []
    for step, (h, a) in states.items():
        for key in ("schema", "step", "time_s", "count", "fields"):
            if key not in h:
                bad.append("step %d: no %s" % (step, key))
        if [(f["name"], f["dtype"]) for f in h["fields"]] != expected_fields or any(
                f["components"] != 1 for f in h["fields"]):
            bad.append("step %d: fields %s" % (step, h["fields"]))
    seqs = [h["seq"] for t, h, a in messages if t == "state"]
    check("state: headers follow the contract, seq increases", not bad and seqs == sorted(set(seqs)),
          "; ".join(bad[:5]) + " seq %s" % seqs[:20])

    # against the run's own snapshots, at every step both have
    compared, mismatches = 0, []
    for name in sorted(os.listdir(run.out)):
        m = re.match(r"snap_(\d+)\.vtp$", name)
        if not m or int(m.group(1)) not in states:
            continue
        snap = vtp.read_vtp(os.path.join(run.out, name))
        h, a = states[int(m.group(1))]
        pairs = [("x_m", snap["points"][:, 0]), ("y_m", snap["points"][:, 1]),
                 ("vx_mps", snap["velocity_mps"][:, 0]), ("vy_mps", snap["velocity_mps"][:, 1]),
                 ("density_kgpm3", snap["density_kgpm3"]), ("pressure_pa", snap["pressure_pa"]),
                 ("kind", snap["kind"]), ("id", snap["id"])]
        if h["count"] != snap["points"].shape[0] or abs(h["time_s"] - snap["time_s"]) > 0:
            mismatches.append("%s: count %d/%d time %r/%r" % (name, h["count"], snap["points"].shape[0],
                                                                h["time_s"], snap["time_s"]))
        for field, expected in pairs:
            if not np.array_equal(a[field], expected):
                mismatches.append("%s: %s differs (max %g)" % (name, field, np.max(np.abs(
                    a[field].astype(float) - expected.astype(float)))))
        compared += 1
    final_step = max(states) if states else -1
    check("state: decoded arrays equal the snapshots bit for bit (first and final included)",
          compared >= 2 and not mismatches and os.path.exists(os.path.join(run.out, "snap_%09d.vtp" % final_step))
          and 0 in states, "compared %d snapshots; %s" % (compared, "; ".join(mismatches[:5])))

    ok_subset = len(subset_messages) > 0
    detail = ""
    for t, h, a in subset_messages:
        if t != subset_topic:
            continue
        if [f["name"] for f in h["fields"]] != ["x_m", "vx_mps"]:
            ok_subset, detail = False, "fields %s" % h["fields"]
        elif h["step"] in states and not (np.array_equal(a["x_m"], states[h["step"]][1]["x_m"]) and
                                          np.array_equal(a["vx_mps"], states[h["step"]][1]["vx_mps"])):
            ok_subset, detail = False, "step %d differs from the full state" % h["step"]
    check("state: a field-subset subscription gets only its fields, equal to the full state", ok_subset,
          detail or "%d subset messages" % len(subset_messages))

    names = [f["name"] for f in bodies[0][0]["fields"]] if bodies else []
    check("state: bodies topic carries count 0 and its documented fields",
          bodies and all(h["count"] == 0 and all(v.size == 0 for v in a.values()) for h, a in bodies)
          and names == ["x_m", "y_m", "angle_rad", "vx_mps", "vy_mps", "omega_radps", "radius_m"], str(names))
    check("state: stats carry time, energies, health and live parameters",
          stats and all({"step", "time_s", "dt_s", "kinetic_energy_jpm", "health", "live"} <= set(h) for h in stats)
          and stats[-1]["health"] == "healthy" and "fluid.viscosity_m2ps" in stats[-1]["live"], str(stats[-1:]))


# ---------------------------------------------------------------------------------------------------------------
def group_control():
    # every message kept (the default queue drops under load, which group stalled covers): this group checks
    # that each published stats message carries the value in force at its step
    run = Surge("control", ["-s", "time.end_s=0.15", "--publish-hz", "0", "--publish-hwm", "1000000"], paused=True)
    ctx = zmq.Context.instance()
    sub = surge_client.subscribe(run.pub, ["stats"], ctx, latest_only=False)
    sub.setsockopt(zmq.RCVHWM, 100000)
    ctl = surge_client.Control(run.ctl, 10)
    first = wait_for(lambda: surge_client.receive(sub, 100), 20)
    # each status reply is served by the solver thread at a step boundary, so five replies in a row span five
    # boundaries whatever the machine's load: a run that did not hold would step between them
    statuses = [ctl.request({"cmd": "status"}) for _ in range(5)]
    check("control: paused at start holds the step", first is not None and
          all(s.get("paused") and s.get("step") == 0 for s in statuses), str(statuses))
    reply = ctl.request({"cmd": "step", "n": 7})
    held = wait_for(lambda: (lambda s: s if s["paused"] and s["step"] == 7 else None)(ctl.request({"cmd": "status"})), 20)
    after = [ctl.request({"cmd": "status"}) for _ in range(5)]
    check("control: step 7 runs exactly 7 steps and pauses",
          reply.get("ok") and held and all(s.get("step") == 7 for s in after), "%s %s %s" % (reply, held, after))
    ctl.request({"cmd": "resume"})
    wait_for(lambda: ctl.request({"cmd": "status"})["step"] >= 60, 30)
    ctl.request({"cmd": "pause"})
    old = ctl.request({"cmd": "get", "key": "fluid.viscosity_m2ps"})["value"]
    new = old * 4
    reply = ctl.request({"cmd": "set", "key": "fluid.viscosity_m2ps", "value": new})
    set_step = reply.get("step")
    check("control: set replies with the value applied, the previous one and the step",
          reply.get("ok") and reply["value"] == new and reply["previous"] == old and set_step >= 60, str(reply))
    # still paused: the change is published at once, before any later step can supersede it in the mailbox
    before_resume = []

    def changed_state_arrived():
        m = surge_client.receive(sub, 100)
        if m:
            before_resume.append(m)
        return m and m[0] == "stats" and m[1]["step"] == set_step and m[1]["live"]["fluid.viscosity_m2ps"] == new

    published_at_once = wait_for(changed_state_arrived, 20)
    check("control: while paused, the change is published at once with the step it applied at",
          published_at_once, "messages: %s" % [(t, h["step"]) for t, h, a in before_resume][-5:])
    ctl.request({"cmd": "resume"})
    messages, finished = collect_until_final(sub, run)
    messages = before_resume + messages
    rc = run.wait()
    check("control: run finishes", rc == 0 and finished, run.describe())
    stats = [h for t, h, a in ([first] if first else []) + messages if t == "stats"]
    # the state of step S may have gone out before the change (applied after step S, while paused there); the
    # change is then published at once, so the last message of step S and every later one show it
    at_set = [h for h in stats if h["step"] == set_step]
    wrong = [(h["step"], h["live"]["fluid.viscosity_m2ps"]) for h in stats
             if h["step"] != set_step and h["live"]["fluid.viscosity_m2ps"] != (new if h["step"] > set_step else old)]
    check("control: stats show the new viscosity from the journaled step on (its last message there), the old "
          "one before", not wrong and at_set and at_set[-1]["live"]["fluid.viscosity_m2ps"] == new
          and any(h["step"] < set_step for h in stats) and any(h["step"] > set_step for h in stats),
          "set at step %s; wrong: %s; at that step: %s" % (set_step, wrong[:10],
                                                          [h["live"]["fluid.viscosity_m2ps"] for h in at_set]))
    journal_path = os.path.join(run.out, "control.jsonl")
    journal = [json.loads(line) for line in open(journal_path)] if os.path.exists(journal_path) else []
    sets = [e for e in journal if e["cmd"] == "set"]
    check("control: the journal records the set with its step and time",
          len(sets) == 1 and sets[0]["step"] == set_step and sets[0]["key"] == "fluid.viscosity_m2ps"
          and float(sets[0]["value"]) == new and [e["cmd"] for e in journal] == ["step", "resume", "pause", "set", "resume"],
          str(journal))
    replay = Surge("control_replay", ["-s", "time.end_s=0.15", "--replay", journal_path], publish=False, control=False)
    replay.wait()
    check("control: replaying the journal reproduces the steered run's state hash",
          replay.rc == 0 and run.state_hash() and replay.state_hash() == run.state_hash(),
          "steered %s, replayed %s\n%s" % (run.state_hash(), replay.state_hash(), replay.describe()))
    plain = Surge("control_plain", ["-s", "time.end_s=0.15"], publish=False, control=False)
    plain.wait()
    check("control: (the change mattered: an unsteered run ends in another state)",
          plain.rc == 0 and plain.state_hash() != run.state_hash(), plain.describe())

    # an output interval set live takes effect at once, even one that was 0 (final snapshot only); a bed set
    # moving live is marked as a moving wall in the outputs from then on
    interval = Surge("control_interval", ["-s", "time.end_s=0.1", "-s", "output.snapshot_interval_s=0"],
                     publish=False, paused=True)
    ctl = surge_client.Control(interval.ctl, 10)
    reply = ctl.request({"cmd": "set", "key": "output.snapshot_interval_s", "value": 0.02})
    belt = ctl.request({"cmd": "set", "key": "walls.bottom_speed_mps", "value": -0.01})
    ctl.request({"cmd": "resume"})
    interval.wait()
    pvd = os.path.join(interval.out, "run.pvd")
    entries = vtp.read_pvd(pvd) if os.path.exists(pvd) else []
    times = [t for t, _ in entries]
    check("control: output.snapshot_interval_s set from 0 to 0.02 s writes a snapshot every 0.02 s",
          reply.get("ok") and interval.rc == 0 and len(times) == 6 and abs(times[1] - 0.02) < 1e-3,
          "reply %s, snapshot times %s\n%s" % (reply, times, interval.describe()))
    kinds = [np.count_nonzero(vtp.read_vtp(os.path.join(interval.out, f))["kind"] == 2) for _, f in entries]
    check("control: a bed set moving live is a moving wall (kind 2) in the snapshots after the change",
          belt.get("ok") and len(kinds) == 6 and kinds[0] == 0 and all(k > 0 for k in kinds[1:]),
          "reply %s, moving-wall particles per snapshot %s" % (belt, kinds))

    # a change made while paused at the step of a periodic checkpoint goes into that checkpoint (the journal lists
    # it at that step, and a restart keeps the journal up to the checkpoint's step)
    held = Surge("control_checkpoint", ["-s", "time.end_s=10", "-s", "output.checkpoint_interval_s=1e-6"],
                 publish=False, paused=True)
    ctl = surge_client.Control(held.ctl, 10)
    ctl.request({"cmd": "step", "n": 3})
    at_3 = wait_for(lambda: (lambda s: s if s["paused"] and s["step"] == 3 else None)(ctl.request({"cmd": "status"})), 20)
    old = ctl.request({"cmd": "get", "key": "fluid.viscosity_m2ps"})["value"]
    reply = ctl.request({"cmd": "set", "key": "fluid.viscosity_m2ps", "value": old * 2})
    checkpoint = os.path.join(held.out, "checkpoint.bin")

    def stored_in_checkpoint():
        """(viscosity, step) of the checkpoint on disk, or (None, None)."""
        try:
            with open(checkpoint, "rb") as f:
                data = f.read()
            plen = struct.unpack_from("<Q", data, 16)[0]
            m = re.search(r"\[fluid\][^\[]*?viscosity_m2ps\s*=\s*([^\s;#]+)", data[24:24 + plen].decode())
            return (float(m.group(1)) if m else None), struct.unpack_from("<q", data, 24 + plen)[0]
        except (OSError, struct.error, UnicodeDecodeError, ValueError):
            return None, None

    # the rewrite follows the reply (after the boundary is served): wait for it, without a fixed sleep
    wait_for(lambda: stored_in_checkpoint()[0] == old * 2 or None, 20)
    held.proc.kill()
    held.wait()
    stored, step = stored_in_checkpoint()
    check("control: a set while paused at a checkpoint's step is in that checkpoint",
          at_3 and reply.get("ok") and step == 3 and stored == old * 2,
          "status %s, reply %s, checkpoint step %s, viscosity %s (set %s)" % (at_3, reply, step, stored, old * 2))

    # a change that makes the flow faster than c0 was derived for is applied, with a warning naming the remedy
    fast = Surge("control_fast", ["-s", "time.end_s=0.1"], publish=False, paused=True)
    ctl = surge_client.Control(fast.ctl, 10)
    slow = ctl.request({"cmd": "set", "key": "walls.bottom_speed_mps", "value": -0.01})
    quick = ctl.request({"cmd": "set", "key": "walls.bottom_speed_mps", "value": -5})
    ctl.request({"cmd": "stop"})
    fast.wait()
    check("control: a belt at 0.01 m/s gets no warning; at 5 m/s (c0 = 19.8 m/s) one that names c0 and the remedy",
          slow.get("ok") and "warning" not in slow and quick.get("ok") and "times the expected speed 5 m/s" in
          quick.get("warning", "") and "numerics.c0_factor" in quick.get("warning", "") and fast.rc == 0,
          "replies %s / %s\n%s" % (slow, quick, fast.describe()))


# ---------------------------------------------------------------------------------------------------------------
BAD_REQUESTS = [  # (request bytes, words the error must contain)
    (b"not json", "not valid JSON"),
    (b'{"cmd": "status", "pad": "' + b"x" * 10000 + b'"}', "request too long (10028 bytes; at most 8192)"),
    (b"", "not valid JSON"),
    (b"[1, 2]", "JSON object"),
    (b'"status"', "JSON object"),
    (b"{}", '"cmd"'),
    (b'{"cmd": 3}', '"cmd"'),
    (b'{"cmd": "explode"}', "unknown command 'explode'"),
    (b'{"cmd": "get"}', '"key" must be a string'),
    (b'{"cmd": "get", "key": "fluid.nope"}', "unknown parameter 'fluid.nope'"),
    (b'{"cmd": "set", "key": "numerics.dp_m", "value": 0.001}', "cannot change while the simulation runs"),
    (b'{"cmd": "set", "key": "fluid.viscosity_m2ps", "value": "thick"}', "must be a number"),
    (b'{"cmd": "set", "key": "fluid.viscosity_m2ps"}', "must be a number"),
    (b'{"cmd": "set", "key": "fluid.viscosity_m2ps", "value": -1}', "fluid.viscosity_m2ps"),
    (b'{"cmd": "set", "key": "body.slope_deg", "value": 1e300}', "body.slope_deg"),
    (b'{"cmd": "set", "key": "shifting.form", "value": "sideways"}', "shifting.form"),
    (b'{"cmd": "set", "key": "shifting.form", "value": 1}', "one of the names"),
    (b'{"cmd": "set", "key": "fluid.viscosity_m2ps", "vlaue": 0.1}', "unexpected member 'vlaue'"),
    (b'{"cmd": "step", "n": 0}', '"n" must be a whole number'),
    (b'{"cmd": "step", "n": 2.5}', '"n" must be a whole number'),
    (b'{"cmd": "step", "n": "many"}', '"n" must be a whole number'),
    (b'{"cmd": "status"} trailing', "not valid JSON"),
    (b'{"cmd": "status\x00"}', "NUL byte"),
    (b'\xff\xfe{"cmd": 1}', "not valid JSON"),
    # an escaped NUL would cut the string; echoed bytes come back as valid UTF-8 (a request's
    # invalid bytes, a character cut by the length limit); D5 numbers and names JSON and the registry do not allow
    (b'{"cmd": "status\\u0000junk"}', "\\u0000"),
    (b'{"cmd": "set", "key": "shifting.form", "value": "none\\u0000junk"}', "\\u0000"),
    (b'{"cmd": "\xff\xfeboom"}', "unknown command '??boom'"),
    (b'{"cmd": "' + "\u20ac".encode() * 100 + b'"}', "unknown command"),
    (b'{"cmd": "set", "key": "health.min_dt_ratio", "value": 01}', "JSON does not allow"),
    (b'{"cmd": "set", "key": "fluid.viscosity_m2ps", "value": +1}', "JSON does not allow"),
    (b'{"cmd": "set", "key": "shifting.form", "value": " none"}', "without spaces"),
]


def group_inputs():
    run = Surge("inputs", ["-s", "time.end_s=0.25"], publish=False, paused=True)
    ctx = zmq.Context.instance()
    ctl = surge_client.Control(run.ctl, 10)
    wrong = []
    for request, words in BAD_REQUESTS:
        try:
            reply = ctl.request(request)
        except TimeoutError:
            reply = {"timeout": True}
        if reply.get("ok") is not False or words not in reply.get("error", ""):
            wrong.append("%r -> %s" % (request, reply))
    check("inputs: every malformed request gets its error reply (%d kinds)" % len(BAD_REQUESTS), not wrong,
          "\n".join(wrong))

    # list's reply is kept between requests: it must follow a change of a parameter
    first = ctl.request({"cmd": "list"})
    ctl.request({"cmd": "set", "key": "fluid.viscosity_m2ps", "value": 0.0025})
    second = ctl.request({"cmd": "list"})

    def viscosity(reply):
        return [p["value"] for p in reply.get("params", []) if p["key"] == "fluid.viscosity_m2ps"]
    check("inputs: list shows a parameter's new value after a set", viscosity(first) != [0.0025]
          and viscosity(second) == [0.0025], "%s then %s" % (viscosity(first), viscosity(second)))

    dealer = ctx.socket(zmq.DEALER)
    dealer.setsockopt(zmq.LINGER, 0)
    dealer.connect(run.ctl)
    dealer.send_multipart([b'{"cmd": "status"}', b'{"cmd": "status"}'])
    multi = json.loads(dealer.recv()) if dealer.poll(5000) else {}
    dealer.send(b'{"cmd": "status"}')  # a DEALER without the empty delimiter is answered the same way
    plain = json.loads(dealer.recv()) if dealer.poll(5000) else {}
    check("inputs: a request of several frames is refused; a DEALER client is served",
          multi.get("ok") is False and "one frame" in multi.get("error", "") and plain.get("ok") is True,
          "%s %s" % (multi, plain))

    big = ctx.socket(zmq.REQ)
    big.setsockopt(zmq.LINGER, 0)
    big.connect(run.ctl)
    big.send(b'{"cmd": "status", "pad": "' + b"x" * 100000 + b'"}')
    for _ in range(2):  # two boundaries served after it: a reply to it, if any, has been sent by now
        ctl.request({"cmd": "status"})
    answered = big.poll(200)
    big.close()
    gone = ctx.socket(zmq.REQ)
    gone.setsockopt(zmq.LINGER, 0)
    gone.connect(run.ctl)
    gone.send(b'{"cmd": "status"}')
    gone.close()  # disconnects before its reply
    status = ctl.request({"cmd": "status"})
    check("inputs: an oversize request drops only its client; a vanished client leaves the socket working",
          not answered and status.get("ok") and status["paused"], "answered=%s status=%s" % (answered, status))

    ctl.request({"cmd": "resume"})
    rc = run.wait()
    check("inputs: after all that the run finishes normally", rc == 0 and "done" in run.stderr, run.describe())

    stopper = Surge("inputs_stop", ["-s", "time.end_s=100"], publish=False)
    c2 = surge_client.Control(stopper.ctl, 10)
    wait_for(lambda: c2.request({"cmd": "status"})["step"] >= 20, 20)
    snap = c2.request({"cmd": "snapshot"})
    reply = c2.request({"cmd": "stop"})
    stopper.wait(30)
    files = os.listdir(stopper.out) if os.path.isdir(stopper.out) else []
    check("inputs: snapshot writes the named file; stop ends the run with exit 0, a checkpoint and a final snapshot",
          reply.get("ok") and stopper.rc == 0 and "stopped by a control request" in stopper.stderr
          and "checkpoint.bin" in files and snap.get("file") in files
          and "snap_%09d.vtp" % reply["step"] in files, "%s\n%s\n%s" % (reply, files, stopper.describe()))

    # bad options and journals: exit 2 and a message naming the problem, before anything runs
    taken = ctx.socket(zmq.PUB)
    port = taken.bind_to_random_port("tcp://127.0.0.1")
    bad_journal = os.path.join(WORK, "bad_journal.jsonl")
    with open(bad_journal, "w") as f:
        f.write('{"step": 3, "time_s": 0, "source": "control", "cmd": "set", "key": "fluid.viscosity_m2ps", '
                '"value": "0.01"}\n{"step": "x", "cmd": "stop"}\n')
    huge_journal = os.path.join(WORK, "huge_journal.jsonl")
    with open(huge_journal, "w") as f:
        f.write('{"step": 1e30, "cmd": "stop"}\n')
    late_journal = os.path.join(WORK, "late_journal.jsonl")
    with open(late_journal, "w") as f:
        f.write('{"step": 2, "cmd": "set", "key": "numerics.dp_m", "value": "0.02"}\n')
    cases = [
        (["--publish", "nonsense"], "--publish needs an endpoint"),
        (["--publish"], "--publish needs an endpoint"),
        (["--control", "0"], "--control needs an endpoint"),
        (["--publish", "tcp://127.0.0.1:%d" % port], "cannot publish on 'tcp://127.0.0.1:%d'" % port),
        (["--control", "ipc:///nonexistent_surge_dir/ctl.sock"], "cannot open the control socket"),
        (["--control", "tcp://999.1.1.1:5"], "can be reached from other machines"),
        (["--publish-every", "0"], "--publish-every needs"),
        (["--publish-hz", "-1"], "--publish-hz needs"),
        (["--publish-hz", "fast"], "--publish-hz needs"),
        (["--publish-hwm", "0"], "--publish-hwm needs"),
        (["--paused"], "--paused needs --control"),
        (["--publish", "5599", "--control", "5599"], "different endpoints"),
        (["--replay", os.path.join(WORK, "missing.jsonl")], "cannot read the journal"),
        (["--replay", bad_journal], "bad_journal.jsonl:2: \"step\" must be a whole number"),
        (["--replay", huge_journal], "huge_journal.jsonl:1: \"step\" must be a whole number in [0, 2^53]"),
    ]
    wrong = []
    for extra, words in cases:
        args = [SURGE, "run", TANK, "-o", os.path.join(WORK, "inputs_bad"), "--overwrite", "-s", "time.end_s=0.01"] + extra
        p = subprocess.run(args, capture_output=True, text=True, timeout=30)
        if p.returncode != 2 or words not in p.stderr:
            wrong.append("%s -> exit %d: %s" % (" ".join(extra), p.returncode, p.stderr.strip()[-300:]))
    p = subprocess.run([SURGE, "run", TANK, "-o", os.path.join(WORK, "inputs_late"), "--overwrite", "-s", "time.end_s=0.01",
                        "--replay", late_journal], capture_output=True, text=True, timeout=30)
    if p.returncode != 2 or "late_journal.jsonl:1: numerics.dp_m cannot change" not in p.stderr:
        wrong.append("late journal -> exit %d: %s" % (p.returncode, p.stderr.strip()[-300:]))
    taken.close()
    check("inputs: bad stream options and journals exit 2 with a message naming them (%d cases)" % (len(cases) + 1),
          not wrong, "\n".join(wrong))

    # one subscriber with 100 junk topics and 100 field selections cannot take a later "stats" subscriber's slot
    # (64 junk subscriptions once filled the table and stats never came)
    hogged = Surge("inputs_hog", ["-s", "time.end_s=100", "--publish-hz", "0"], paused=True)
    hog = surge_client.subscribe(hogged.pub, ["junk%d" % i for i in range(100)] +
                                 ["state/junk%d" % i for i in range(100)], ctx, latest_only=True)
    time.sleep(1.0)  # the publisher reads the hog's subscriptions first
    late = surge_client.subscribe(hogged.pub, ["stats"], ctx, latest_only=False)
    hctl = surge_client.Control(hogged.ctl, 10)
    got = wait_for(lambda: (hctl.request({"cmd": "step", "n": 1}), surge_client.receive(late, 200))[1], 30)
    hctl.request({"cmd": "stop"})
    hogged.wait(60)
    hog.close()
    late.close()
    check("inputs: a subscriber holding 200 useless subscriptions leaves room for a later stats subscriber",
          got is not None, hogged.describe())

    # idle TCP connections cannot take the file descriptors the outputs need: the run starts with
    # a soft limit of 256 open files, 400 plain connections arrive at its control and publisher ports, and it must
    # still write every snapshot and finish. It starts paused and is resumed once the connections are held, so a
    # fast machine cannot finish the run before they arrive; 1 s of flow, so that it does not end (closing its control
    # socket, which gives a queued reply 200 ms) before the resume's reply has left on a busy machine
    import resource
    import socket
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    hard = resource.getrlimit(resource.RLIMIT_NOFILE)[1]
    out = os.path.join(WORK, "inputs_fds")
    shutil.rmtree(out, ignore_errors=True)
    proc = subprocess.Popen([SURGE, "run", TANK, "-o", out, "--threads", "1", "-s", "time.end_s=1", "-s",
                             "output.snapshot_interval_s=0.03", "-s", "output.progress_interval_s=0", "--control",
                             str(port), "--publish", str(port + 1), "--paused"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"),
                            preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_NOFILE, (min(256, hard), hard)))
    held = []
    deadline = time.time() + 20
    while len(held) < 400 and time.time() < deadline and proc.poll() is None:
        for target in (port, port + 1):
            try:
                held.append(socket.create_connection(("127.0.0.1", target), timeout=1))
            except OSError:
                time.sleep(0.01)
    resume = ctx.socket(zmq.REQ)
    resume.setsockopt(zmq.LINGER, 0)
    resume.connect("tcp://127.0.0.1:%d" % port)
    resume.send(b'{"cmd": "resume"}')
    resumed = resume.poll(20000)
    resume.close()
    try:
        _, err_text = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err_text = proc.communicate()
    for c in held:
        c.close()
    snaps = [f for f in os.listdir(out) if f.startswith("snap_")] if os.path.isdir(out) else []
    check("inputs: 400 idle TCP connections under a 256-file limit cost no output (%d connected)" % len(held),
          proc.returncode == 0 and len(held) >= 300 and len(snaps) >= 25 and resumed,
          "exit %s, %d snapshots, resume answered %s: %s" % (proc.returncode, len(snaps), bool(resumed),
                                                             (err_text or "").strip()[-400:]))

# ---------------------------------------------------------------------------------------------------------------
def group_peers():
    """400 connections opened at once against a run whose soft and hard limits are 256 open files (sh's ulimit
    sets both, so the run cannot raise its own): half of them raw TCP that never sends ZeroMQ's greeting, half
    ZeroMQ DEALER clients that complete it and then send nothing. The run must go on stepping and write its
    snapshots while they are held (no "Too many open files"), and a client connecting after them must be answered
    once the idle ones have been closed."""
    import resource
    import signal
    import socket
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    resource.setrlimit(resource.RLIMIT_NOFILE, (max(soft, min(hard, 4096)), hard))  # this script holds 600 fds
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    out = os.path.join(WORK, "peers")
    shutil.rmtree(out, ignore_errors=True)
    command = [SURGE, "run", TANK, "-o", out, "--threads", "1", "-s", "time.end_s=100", "-s",
               "output.snapshot_interval_s=0.01", "-s", "output.progress_interval_s=0", "--control", str(port),
               "--publish", str(port + 1)] + SCHEME
    stderr_path = os.path.join(WORK, "peers_stderr.txt")
    proc = subprocess.Popen(["sh", "-c", 'ulimit -n 256 && exec "$@"', "sh"] + command, stdout=subprocess.DEVNULL,
                            stderr=open(stderr_path, "w"), env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))

    def snapshots():
        return len([f for f in os.listdir(out) if f.startswith("snap_") and f.endswith(".vtp")]) \
            if os.path.isdir(out) else 0

    started = wait_for(lambda: snapshots() >= 3 or proc.poll() is not None, 60) and proc.poll() is None
    ctx = zmq.Context()
    ctx.setsockopt(zmq.MAX_SOCKETS, 1024)
    raw, dealers = [], []
    for k in range(200):  # all at once: non-blocking connects, nothing waits for an accept
        s = socket.socket()
        s.setblocking(False)
        s.connect_ex(("127.0.0.1", port if k % 2 == 0 else port + 1))
        raw.append(s)
        d = ctx.socket(zmq.DEALER)
        d.setsockopt(zmq.LINGER, 0)
        d.setsockopt(zmq.RECONNECT_IVL, 1000)  # a closed peer comes back, once a second
        d.connect("tcp://127.0.0.1:%d" % port)
        dealers.append(d)
    before = snapshots()
    time.sleep(4.0)  # the flood is held: 2 s of ZeroMQ's greeting timeout, and more
    during = snapshots() - before
    alive = proc.poll() is None
    late = surge_client.Control("tcp://127.0.0.1:%d" % port, 2, ctx)
    reply = None
    deadline = time.time() + 40
    while reply is None and time.time() < deadline and proc.poll() is None:
        try:
            reply = late.request({"cmd": "status"})
        except TimeoutError:
            late = surge_client.Control("tcp://127.0.0.1:%d" % port, 2, ctx)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        proc.wait(60)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
    for s in raw:
        s.close()
    for d in dealers:
        d.close()
    ctx.destroy(linger=0)
    err_text = open(stderr_path).read()
    check("peers: 400 connections at once under a 256-file limit: the run steps on and writes its snapshots "
          "(%d snapshots while they were held)" % during,
          started and alive and during >= 5 and "Too many open files" not in err_text
          and "interrupted; checkpoint written" in err_text,
          "started %s, alive after the flood %s, exit %s: %s" % (started, alive, proc.returncode, err_text[-600:]))
    check("peers: a client arriving after the flood is answered once the idle peers are closed",
          reply is not None and reply.get("ok") is True, "reply %s; %s" % (reply, err_text[-300:]))


# ---------------------------------------------------------------------------------------------------------------
def group_stalled():
    """A subscriber that never reads does not hold the solver back: the run finishes (a blocked publisher would
    hang it, and Surge.wait gives up after 300 s), and the publisher dropped states for that subscriber. The
    subscription is shown live first (the paused run's step-0 state arrives), so the drop is not a subscription
    that never connected. Step rates are measured in tools/stream_bench.py, not here."""
    case_args = ["-s", "numerics.dp_m=0.004", "-s", "time.end_s=0.06", "-s", "output.snapshot_interval_s=0",
                 "-s", "output.progress_interval_s=1000", "--publish-hz", "0", "--publish-hwm", "2"]
    stalled = Surge("stalled", case_args, paused=True)
    sub = zmq.Context.instance().socket(zmq.SUB)
    sub.setsockopt(zmq.RCVHWM, 1)
    sub.setsockopt(zmq.RCVBUF, 4096)
    sub.connect(stalled.pub)
    sub.setsockopt(zmq.SUBSCRIBE, b"state")
    first = wait_for(lambda: sub.recv_multipart() if sub.poll(100) else None, 20)
    surge_client.Control(stalled.ctl, 10).request({"cmd": "resume"})  # from here the subscriber never reads
    stalled.wait(300)
    received = 0
    while sub.poll(500):
        sub.recv_multipart()
        received += 1
    sub.close()
    published = re.search(r"published (\d+) states", stalled.stderr)
    if not check("stalled: the subscription is live (the paused run's first state arrived) and the run finishes",
                 first is not None and stalled.rc == 0 and published, stalled.describe()):
        return
    print("stalled: %s states published, %d reached the stalled subscriber after the first" %
          (published.group(1), received))
    check("stalled: the publisher dropped states for the stalled subscriber instead of waiting",
          received < int(published.group(1)) - 1, "%d of %s" % (received, published.group(1)))


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def first_topic(sub, topic, limit_s):
    """Seconds until a message with exactly this topic arrived on sub, or None after limit_s."""
    start = time.time()
    while time.time() - start < limit_s:
        if sub.poll(100) and sub.recv_multipart()[0] == topic.encode():
            return time.time() - start
    return None


def group_subsets():
    """Subscriptions cannot hold a field subset hostage, over TCP on 127.0.0.1: a peer's 40 junk "state/..."
    subscriptions (unknown fields, a trailing comma, a repeated field) and 100 valid distinct subsets do not keep
    a state/x_m,y_m subscriber (tools/surge_watch.py's) from its topic, while that peer is there and, for a new
    subscriber, after it left; the valid subsets take turns, at most 16 per state; the log names that limit and
    the junk."""
    port = free_port()
    run = Surge("subsets", ["-s", "time.end_s=1000", "-s", "output.snapshot_interval_s=0", "--publish-hz", "0",
                            "--publish-hwm", "1000", "--publish", "tcp://127.0.0.1:%d" % port])
    endpoint = "tcp://127.0.0.1:%d" % port
    ctx = zmq.Context.instance()
    fields = ["x_m", "y_m", "vx_mps", "vy_mps", "density_kgpm3", "pressure_pa", "kind", "id"]
    junk = ["state/junk%d" % i for i in range(37)] + ["state/x_m,", "state/x_m,x_m", "state/x_m,,y_m"]
    valid = ["state/" + ",".join(c) for c in itertools.permutations(fields, 3)][:100]
    hog = ctx.socket(zmq.SUB)
    hog.setsockopt(zmq.RCVHWM, 100000)
    hog.connect(endpoint)
    for topic in junk + valid + ["stats"]:
        hog.setsockopt(zmq.SUBSCRIBE, topic.encode())
    # the hog's subscriptions reach the publisher in order: its first stats message comes after all of them
    hog_ready = first_topic(hog, "stats", 30)
    watcher = surge_client.subscribe(endpoint, ["state/x_m,y_m"], ctx, latest_only=False)
    with_hog = first_topic(watcher, "state/x_m,y_m", 20)
    per_state = {}
    deadline = time.time() + 3
    while time.time() < deadline:
        if hog.poll(100):
            topic, header, *_ = hog.recv_multipart()
            if topic.startswith(b"state/"):
                per_state.setdefault(json.loads(header)["seq"], set()).add(topic)
    hog.close(0)
    time.sleep(0.5)  # the hog's disconnection reaches the publisher
    newcomer = surge_client.subscribe(endpoint, ["state/x_m,y_m"], ctx, latest_only=False)
    after_hog = first_topic(newcomer, "state/x_m,y_m", 20)
    watcher.close(0)
    newcomer.close(0)
    time.sleep(0.5)
    alone = surge_client.subscribe(endpoint, ["state/x_m,y_m"], ctx, latest_only=False)
    after_all = first_topic(alone, "state/x_m,y_m", 20)
    alone.close(0)
    stopped = surge_client.Control(run.ctl, 10).request({"cmd": "stop"})
    run.wait()
    check("subsets: the run ran and stopped on request", hog_ready is not None and stopped.get("ok") and run.rc == 0,
          run.describe())
    print("subsets: state/x_m,y_m after %s s beside the hog, %s s for a newcomer after it left, %s s alone" %
          (with_hog, after_hog, after_all))
    check("subsets: state/x_m,y_m arrives within 20 s beside a peer holding 40 junk and 100 valid subsets",
          with_hog is not None, run.describe())
    check("subsets: ... and for a new subscriber after that peer left, and after every subscriber left",
          after_hog is not None and after_all is not None, run.describe())
    most = max((len(t) for t in per_state.values()), default=0)
    served = set().union(*per_state.values()) & {t.encode() for t in valid}
    check("subsets: at most 16 subsets per state, taking turns (the hog's valid subsets all served in 3 s)",
          0 < most <= 16 and len(served) == len(valid), "%d subsets at most per state, %d of %d served" %
          (most, len(served), len(valid)))
    check("subsets: the log names the junk not kept and the limit of 16 subsets per state",
          "not keeping the subscription 'state/junk0'" in run.stderr and "further ones are not shown" in run.stderr
          and "more than 16 distinct field subsets" in run.stderr and "more than 64" not in run.stderr,
          run.stderr[-2000:])


def pipelined(endpoint, count, quiet_s, read_after_s=0.0, on_sent=None):
    """A DEALER client that sends count status requests without waiting for replies, reading none before
    read_after_s and then all of them until none came for quiet_s (limit: 120 s); on_sent() is called once every
    request is sent. Its receive queue is kept short, so replies it does not read fill the run's queue to it.
    Returns (requests sent, the replies: JSON objects, or the bytes that were not one)."""
    ctx = zmq.Context.instance()
    sock = ctx.socket(zmq.DEALER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.RCVHWM, 1)
    sock.setsockopt(zmq.RCVBUF, 4096)
    sock.connect(endpoint)
    start = time.time()
    sent, replies, last = 0, [], time.time()
    while time.time() - start < 120:
        if sent < count:
            try:
                sock.send(b'{"cmd": "status"}', zmq.NOBLOCK)
                sent += 1
                if sent == count and on_sent:
                    on_sent()
                continue
            except zmq.Again:
                pass
        if time.time() - start >= read_after_s and sock.poll(10):
            data = sock.recv()
            try:
                replies.append(json.loads(data))
            except ValueError:
                replies.append(data)
            last = time.time()
        elif sent == count and time.time() - max(last, start + read_after_s) > quiet_s:
            break
        elif sent < count:
            time.sleep(0.001)
    sock.close()
    return sent, replies


def group_replies():
    """Control work is budgeted by its cost in time, so requests wait; each must still get exactly one reply.
    1. A client sends 5000 status requests to a paused run and reads nothing for 3 s: ZeroMQ's queue to it fills
       (1000 replies), and the requests after that are refused with "busy" (not run) instead of their replies being
       dropped.
    2. Once the run is resumed, a client sends 600 requests and reads as it goes: they wait for the run's time and
       all are answered.
    3. A client sends 2000 requests and reads as it goes while another client's stop ends the run: every request
       still waiting then is refused with "the run has ended". Replies are counted per client."""
    run = Surge("replies", ["-s", "time.end_s=1000", "-s", "output.snapshot_interval_s=0"], publish=False,
                paused=True)
    ctl = surge_client.Control(run.ctl, 10)
    started = ctl.request({"cmd": "status"}).get("ok")

    def kinds(replies):
        counted = {}
        for r in replies:
            kind = "not JSON" if not isinstance(r, dict) else "ok" if r.get("ok") is True else \
                "busy" if str(r.get("error", "")).startswith("busy:") else \
                "ended" if str(r.get("error", "")).startswith("the run has ended") else "other error"
            counted[kind] = counted.get(kind, 0) + 1
        return counted

    # paused, the run answers requests as fast as they come (a running one spends 2 % of its time on them)
    sent, replies = pipelined(run.ctl, 5000, quiet_s=3, read_after_s=3)
    check("replies: a client that reads nothing for 3 s gets one reply to each of its %d requests (%s)" %
          (sent, kinds(replies)), started and sent == 5000 and len(replies) == sent and
          set(kinds(replies)) <= {"ok", "busy"}, "%d replies to %d requests" % (len(replies), sent))
    resumed = ctl.request({"cmd": "resume"})
    # running, requests beyond the run's time for them wait and are answered at later steps
    sent, replies = pipelined(run.ctl, 600, quiet_s=3)
    check("replies: a running run answers each of %d pipelined requests, later ones at later steps (%s)" %
          (sent, kinds(replies)), resumed.get("ok") and sent == 600 and kinds(replies) == {"ok": 600},
          "%d replies to %d requests" % (len(replies), sent))

    stop_reply = {}

    def stop():
        try:
            stop_reply.update(surge_client.Control(run.ctl, 20).request({"cmd": "stop"}))
        except TimeoutError:
            stop_reply["timeout"] = True
    # the stop goes from its own thread, so that this client keeps reading while it waits for the stop's reply (the
    # run refuses what is left after it ends while its clients read; one that stops reading for 1 s misses the rest)
    stopper = threading.Thread(target=stop)
    sent, replies = pipelined(run.ctl, 2000, quiet_s=3, on_sent=stopper.start)
    stopper.join(30)
    rc = run.wait(60)
    check("replies: requests waiting when a stop ends the run are each answered or refused (%s; stop %s)" %
          (kinds(replies), "answered" if stop_reply.get("ok") else stop_reply),
          resumed.get("ok") and sent == 2000 and len(replies) == sent and
          set(kinds(replies)) <= {"ok", "busy", "ended"} and stop_reply.get("ok") is True,
          "%d replies to %d requests" % (len(replies), sent))
    check("replies: the run ended on the stop request", rc == 0 and "stopped by a control request" in run.stderr,
          run.describe())


def group_ending():
    """When a run ends, the control socket refuses what still comes, but no client can keep the run from exiting.
    1. A client sends 3000 requests to a paused run and never reads; another's stop ends the run. The replies owed
       to the first cannot go out: the run leaves them once that client has read nothing for 1 s, exits, and says
       how many it left.
    2. A client keeps sending requests and reading the replies while a stop ends a running run: each request after
       the end is refused, and the socket closes 5 s after the end all the same; the run exits and says so.
    A run that waited on either client would not exit: each wait here is limited to 60 s."""
    run = Surge("ending_stalled", ["-s", "time.end_s=1000", "-s", "output.snapshot_interval_s=0"], publish=False,
                paused=True)
    ctl = surge_client.Control(run.ctl, 20)
    started = ctl.request({"cmd": "status"}).get("ok")
    silent = zmq.Context.instance().socket(zmq.DEALER)
    silent.setsockopt(zmq.LINGER, 0)
    silent.setsockopt(zmq.RCVHWM, 1)
    silent.setsockopt(zmq.RCVBUF, 4096)
    silent.connect(run.ctl)
    sent = 0
    deadline = time.time() + 30
    while sent < 3000 and time.time() < deadline:
        try:
            silent.send(b'{"cmd": "status"}', zmq.NOBLOCK)
            sent += 1
        except zmq.Again:
            time.sleep(0.001)
    stopped = ctl.request({"cmd": "stop"})
    rc = run.wait(60)
    silent.close()
    left = re.search(r"control: (\d+) repl(?:y|ies) not delivered to 1 client that read nothing for 1 s", run.stderr)
    check("ending: a client that never reads its %d replies does not keep the run from exiting (%s)" %
          (sent, left.group(0) if left else "no such line"),
          started and sent == 3000 and stopped.get("ok") is True and rc == 0 and left is not None and
          int(left.group(1)) > 0, run.describe())

    run = Surge("ending_endless", ["-s", "time.end_s=1000", "-s", "output.snapshot_interval_s=0"], publish=False)
    replies, done = [], threading.Event()

    def endless():
        sock = zmq.Context.instance().socket(zmq.DEALER)
        sock.setsockopt(zmq.LINGER, 0)
        sock.connect(run.ctl)
        while not done.is_set():
            sock.send(b'{"cmd": "status"}')
            while sock.poll(20):
                replies.append(json.loads(sock.recv()))
        sock.close()
    client = threading.Thread(target=endless)
    client.start()
    answered = wait_for(lambda: any(r.get("ok") for r in replies), 30)
    stopped = surge_client.Control(run.ctl, 20).request({"cmd": "stop"})
    rc = run.wait(60)
    done.set()
    client.join(10)
    ended = sum(1 for r in replies if str(r.get("error", "")).startswith("the run has ended"))
    refused = re.search(r"control: refused (\d+) requests? that waited or came after the run ended", run.stderr)
    closed = re.search(r"control: (closed 5 s after the run ended, requests still coming|.*5 s after the end)",
                       run.stderr)
    check("ending: a client that keeps sending after the end is refused (%d refusals read) and the socket closes "
          "5 s after the end (%s)" % (ended, closed.group(0) if closed else "no such line"),
          answered and stopped.get("ok") is True and rc == 0 and ended > 0 and refused is not None and
          int(refused.group(1)) >= ended and closed is not None, run.describe())


def raw_subscriber(port, frames):
    """A ZeroMQ peer written by hand (ZMTP 3.0, NULL security, socket type SUB) over TCP: it sends the given
    frames as they are, such as b"\\x00topic", an unsubscribe that a SUB or XSUB socket would never pass on for a
    topic it did not subscribe to. Returns the connected socket (close it to leave)."""
    s = socket.create_connection(("127.0.0.1", port), timeout=5)
    s.sendall(b"\xff" + b"\x00" * 8 + b"\x7f" + b"\x03\x00" + b"NULL".ljust(20, b"\x00") + b"\x00" * 32)
    greeting = b""
    while len(greeting) < 64:
        chunk = s.recv(64 - len(greeting))
        if not chunk:
            raise OSError("the publisher closed the connection during the greeting")
        greeting += chunk
    ready = b"\x05READY" + b"\x0bSocket-Type" + struct.pack(">I", 3) + b"SUB"
    s.sendall(b"\x04" + bytes([len(ready)]) + ready)
    for frame in frames:
        s.sendall(b"\x00" + bytes([len(frame)]) + frame)
    return s


def newest_seq(sub, topic, limit_s):
    """The highest seq among the messages of this topic that arrive on sub within limit_s (None if none)."""
    best, deadline = None, time.time() + limit_s
    while time.time() < deadline:
        m = surge_client.receive(sub, 50)
        if m and m[0] == topic:
            best = max(best or 0, m[1]["seq"])
    return best


def topic_after(sub, topic, seq, limit_s):
    """Whether a message of this topic with a seq of at least seq arrives on sub within limit_s."""
    deadline = time.time() + limit_s
    while time.time() < deadline:
        m = surge_client.receive(sub, 100)
        if m and m[0] == topic and m[1]["seq"] >= seq:
            return True
    return False


def group_strays():
    """ZeroMQ tells an XPUB socket of every unsubscribe message a peer sends, also for a topic that peer never
    subscribed to (libzmq passes them on: it cannot tell them from a last subscriber leaving). A hand-written peer
    sending such unsubscribes, and one that subscribes once and unsubscribes twice, must not stop the topics other
    clients hold: plain topics (state, stats) and a field subset (state/x_m,y_m). A bodies subscriber gives the
    publisher's current seq; each held topic must arrive again after it. Then the subset's one real holder
    unsubscribes and the subset is no longer sent (a state/ prefix subscriber sees every subset sent)."""
    port = free_port()
    endpoint = "tcp://127.0.0.1:%d" % port
    run = Surge("strays", ["-s", "time.end_s=1000", "-s", "output.snapshot_interval_s=0", "--publish-hz", "0",
                           "--publish", endpoint])
    ctx = zmq.Context.instance()
    subs = {t: surge_client.subscribe(endpoint, [t], ctx, latest_only=False)
            for t in ("state/x_m,y_m", "stats", "state")}
    reference = surge_client.subscribe(endpoint, ["bodies"], ctx, latest_only=False)
    every_subset = surge_client.subscribe(endpoint, ["state/"], ctx, latest_only=False)
    started = [first_topic(sub, t, 30) for t, sub in subs.items()] + [first_topic(reference, "bodies", 10)]
    print("strays: seconds to each first message: %s" % started)
    started = None not in started
    strays = [b"\x00state/x_m,y_m", b"\x00stats", b"\x00state", b"\x00state/", b"\x00", b"\x00s", b"\x00st"]
    twice = [b"\x01state/x_m,y_m", b"\x00state/x_m,y_m", b"\x00state/x_m,y_m",
             b"\x01stats", b"\x00stats", b"\x00stats", b"\x01state", b"\x00state", b"\x00state"]
    peers = [raw_subscriber(port, strays), raw_subscriber(port, twice), raw_subscriber(port, strays * 3)]
    time.sleep(1.0)  # the publisher thread reads them (it looks every 20 ms)
    seq = newest_seq(reference, "bodies", 0.5)
    kept = {t: seq is not None and topic_after(sub, t, seq, 10) for t, sub in subs.items()}
    seen = seq is not None and topic_after(every_subset, "state/x_m,y_m", seq, 5)  # the prefix sees it while held
    for p in peers:
        p.close()
    check("strays: the run publishes and every subscriber got its topic first", started,
          open(run.stderr_path).read()[-1000:])
    check("strays: unsubscribes from peers that did not hold a topic leave other subscribers served (%s)" %
          ", ".join("%s %s" % (t, "kept" if k else "LOST") for t, k in kept.items()),
          started and all(kept.values()), "after seq %s" % seq)

    # the subset's last real holder leaves it: the publisher stops sending it (the prefix subscriber sees none)
    subs["state/x_m,y_m"].setsockopt(zmq.UNSUBSCRIBE, b"state/x_m,y_m")
    time.sleep(1.0)
    newest_seq(every_subset, "state/x_m,y_m", 0.2)  # drop what was queued before the unsubscribe arrived
    seq = newest_seq(reference, "bodies", 0.5)
    still_sent = seq is not None and topic_after(every_subset, "state/x_m,y_m", seq + 1, 2)
    check("strays: a genuine unsubscribe by the subset's last holder releases it (no more state/x_m,y_m sent)",
          seen and seq is not None and not still_sent, "sent while held %s; seq %s, still sent %s" %
          (seen, seq, still_sent))
    for sub in list(subs.values()) + [reference, every_subset]:
        sub.close(0)
    stopped = surge_client.Control(run.ctl, 10).request({"cmd": "stop"})
    run.wait()
    check("strays: the run stopped on request", stopped.get("ok") and run.rc == 0, run.describe())


def group_endpoints():
    """Every TCP loopback form the docs accept binds, the control socket and the publisher alike, and the log names
    the endpoint bound with the port a wildcard got: a status request and a subscription through it are
    answered."""
    port = free_port()
    forms = [("tcp://localhost:%d" % port, "tcp://localhost:*"), ("tcp://[::1]:*", "tcp://[::1]:*"),
             ("tcp://127.0.0.1:*", "tcp://127.0.0.1:*"), (str(free_port()), "tcp://127.0.0.1:*")]
    ctx = zmq.Context.instance()
    for control, publish in forms:
        run = Surge("endpoints", ["-s", "time.end_s=1000", "--control", control, "--publish", publish],
                    publish=False, control=False, paused=True)

        def log_line(words):
            with open(run.stderr_path) as f:
                m = re.search(words + r" (\S+)", f.read())
            return m.group(1) if m else None
        bound = wait_for(lambda: (log_line("control socket on"), log_line("stats on")) if log_line("stats on") and
                         log_line("control socket on") else None, 20) or (None, None)
        reply, stats = {}, None
        if bound[0] and "*" not in bound[0] and "*" not in bound[1]:
            sub, req = ctx.socket(zmq.SUB), ctx.socket(zmq.REQ)
            for sock, endpoint in ((sub, bound[1]), (req, bound[0])):
                sock.setsockopt(zmq.IPV6, 1)
                sock.setsockopt(zmq.LINGER, 0)
                sock.connect(endpoint)
            sub.setsockopt(zmq.SUBSCRIBE, b"stats")
            stats = sub.recv_multipart() if sub.poll(10000) else None
            req.send_json({"cmd": "stop"})
            reply = req.recv_json() if req.poll(10000) else {"error": "no reply"}
            sub.close()
            req.close()
        if not reply.get("ok"):
            run.proc.kill()
        run.wait(60)
        check("endpoints: --control %s and --publish %s bind, the log names the ports bound (%s, %s), a request "
              "and a subscriber are answered through them" % (control, publish, bound[0], bound[1]),
              reply.get("ok") and stats is not None and run.rc == 0 and all(re.search(r":[0-9]+$", b) for b in bound),
              "reply %s\n%s" % (reply, run.describe()))


def group_curve():
    import zmq.auth
    keys = os.path.join(WORK, "curve_keys")
    shutil.rmtree(keys, ignore_errors=True)
    os.makedirs(os.path.join(keys, "clients"))

    def keygen(name):
        return subprocess.run([SURGE, "keygen", os.path.join(keys, name)], capture_output=True, text=True)

    made = [keygen(n) for n in ("run", "clients/alice", "clients/bob", "mallory")]
    secret_mode = os.stat(os.path.join(keys, "run.key")).st_mode & 0o777
    run_key_before = open(os.path.join(keys, "run.key")).read()
    again = keygen("run")
    public, secret = zmq.auth.load_certificate(os.path.join(keys, "run.key"))
    public_only, no_secret = zmq.auth.load_certificate(os.path.join(keys, "run.pub"))
    check("curve: keygen writes NAME.key (mode 0600) and NAME.pub, which pyzmq's zmq.auth reads",
          all(m.returncode == 0 for m in made) and secret_mode == 0o600 and len(public) == 40 and
          len(secret) == 40 and public_only == public and no_secret is None,
          "rc %s, mode %o, keys %r %r" % ([m.returncode for m in made], secret_mode, public, public_only))
    check("curve: keygen never replaces a key file", again.returncode != 0 and "already exists" in again.stderr and
          open(os.path.join(keys, "run.key")).read() == run_key_before, again.stderr)

    def key(name):
        return os.path.join(keys, name)
    secured = ["--curve-key", key("run.key"), "--curve-clients", key("clients")]
    run = Surge("curve", ["-s", "time.end_s=0.05"] + secured, paused=True)
    alice = surge_client.curve_keys(key("run.pub"), key("clients/alice.key"))
    mallory = surge_client.curve_keys(key("run.pub"), key("mallory.key"))
    answered = {}
    for name, curve in (("alice", alice), ("mallory", mallory), ("plain", None)):
        try:
            answered[name] = surge_client.Control(run.ctl, 2 if name != "alice" else 20, curve=curve).request(
                {"cmd": "status"}).get("ok")
        except TimeoutError:
            answered[name] = None
    check("curve: the run answers an allowed client only (not an unknown key, not a plain client)",
          answered == {"alice": True, "mallory": None, "plain": None}, str(answered))
    subs = {n: surge_client.subscribe(run.pub, ["state"], curve=c) for n, c in (("bob", surge_client.curve_keys(
        key("run.pub"), key("clients/bob.key"))), ("mallory", mallory), ("plain", None))}
    surge_client.Control(run.ctl, 20, curve=alice).request({"cmd": "resume"})
    rc = run.wait()
    got = {n: surge_client.receive(s, 3000 if n == "bob" else 500) is not None for n, s in subs.items()}
    check("curve: states reach an allowed subscriber only; the run finishes and reports the refusals",
          got == {"bob": True, "mallory": False, "plain": False} and rc == 0 and
          "is not in the allow-list" in run.stderr and re.search(r"refused \d+ connection", run.stderr),
          "%s\n%s" % (got, run.describe()))

    def cli(*extra):
        return subprocess.run([SURGE, "run", "-o", os.path.join(WORK, "curve_cli"), "--overwrite", "--threads", "1",
                               "-s", "time.end_s=0.001", "-s", "output.progress_interval_s=0"] + list(extra),
                              capture_output=True, text=True, timeout=120)
    with open(key("bad.key"), "w") as f:
        f.write('curve\n    public-key = "tooshort"\n')
    os.makedirs(key("empty"), exist_ok=True)
    bad = [(("--control", "tcp://0.0.0.0:*"), "refused"),
           (("--control", "5599", "--curve-key", key("run.key")), "--curve-key needs --curve-clients"),
           (("--control", "5599", "--curve-clients", key("clients")), "--curve-clients needs --curve-key"),
           (("--control", "tcp://0.0.0.0:*", "--curve-key", key("run.pub"), "--curve-clients", key("clients")),
            "holds no secret-key"),
           (("--control", "tcp://0.0.0.0:*", "--curve-key", key("bad.key"), "--curve-clients", key("clients")),
            "bad.key line 2"),
           (("--control", "tcp://0.0.0.0:*", "--curve-key", key("run.key"), "--curve-clients", key("empty")),
            "holds no *.pub"),
           (("--control", "tcp://0.0.0.0:*", "--curve-key", key("run.key"), "--curve-clients", key("nothing")),
            "nothing: No such file"),
           (("--curve-key", key("run.key"), "--curve-clients", key("clients")), "neither is given")]
    wrong = []
    for args, words in bad:
        r = cli(*args)
        if r.returncode != 2 or words not in r.stderr:
            wrong.append("%s -> %d %s" % (" ".join(args), r.returncode, r.stderr.strip()[-300:]))
    check("curve: bad keys, lone key options and an open --control without keys are refused with the reason",
          not wrong, "\n".join(wrong))
    remote = cli("--control", "tcp://0.0.0.0:*", *secured)
    warned = cli("--publish", "tcp://0.0.0.0:*")
    check("curve: a --control reachable from elsewhere runs with keys; an open --publish is warned about",
          remote.returncode == 0 and warned.returncode == 0 and "no authentication" in warned.stderr,
          "%d %s\n%d %s" % (remote.returncode, remote.stderr[-400:], warned.returncode, warned.stderr[-400:]))


groups = {"curve": group_curve, "state": group_state, "control": group_control, "inputs": group_inputs,
          "stalled": group_stalled, "peers": group_peers, "subsets": group_subsets, "endpoints": group_endpoints,
          "strays": group_strays, "replies": group_replies, "ending": group_ending}
os.makedirs(WORK, exist_ok=True)
groups[sys.argv[4]]()
sys.exit(finish())
