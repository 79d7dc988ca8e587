#!/usr/bin/python3
"""stream_bench: what publishing live state costs the solver, and the largest state rate a subscriber gets.

  tools/stream_bench.py [--surge build/surge] [--threads 2] [--end-s 0.03] [--repeat 3] [--out runs/stream_bench]

Runs the benchmark scene (cases/incline_film.ini, 20,000 fluid particles) for --end-s of simulated time in
these configurations, one after the other in this one invocation:
  alone         --publish, no subscriber (nothing is copied out of the solver)
  no-publish    no --publish at all
  fast-all      a subscriber taking every state with all fields (--publish-every 1 --publish-hz 0)
  fast-30hz     the same subscriber at the default cadence (at most 30 states per wall-clock second)
  stalled       a subscriber that connects and never reads (--publish-every 1 --publish-hz 0)
and the small still tank (1,472 particles) with fast-all, where the solver is fast enough that the stream is the
limit. Each run starts paused with a control socket and is resumed once the subscriber is connected, so all
rates cover the same span. The configurations are run in turn --repeat times (interleaved, so a slow spell of
the machine does not fall on one of them only) and the table gives the median of each: solver steps/s, its
ratio to "alone", states received per second and MB/s. The subscriber is Python (python/surgepy/client.py) decoding every field with numpy.
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import threading
import time

import zmq

from surgepy import cli_checks
from surgepy import client as surge_client

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Subscriber(threading.Thread):
    """Receives and decodes state messages until the final stats message (or never reads, if stalled)."""

    def __init__(self, endpoint, stalled):
        super().__init__(daemon=True)
        self.sock = zmq.Context.instance().socket(zmq.SUB)
        self.sock.setsockopt(zmq.RCVHWM, 1 if stalled else 1000)
        self.sock.connect(endpoint)
        self.sock.setsockopt(zmq.SUBSCRIBE, b"state")
        self.sock.setsockopt(zmq.SUBSCRIBE, b"stats")
        self.stalled, self.done = stalled, threading.Event()
        self.states = self.bytes = 0
        self.first = self.last = None

    def run(self):
        if self.stalled:
            self.done.wait()
            return
        while not self.done.is_set():
            if not self.sock.poll(100):
                continue
            parts = self.sock.recv_multipart()
            topic, header, _ = surge_client.decode(parts)
            if topic == "state":
                now = time.time()
                self.first = self.first or now
                self.last = now
                self.states += 1
                self.bytes += sum(len(p) for p in parts)
            elif header["status"] == "final":
                return

    def rates(self):
        span = (self.last - self.first) if self.states > 1 else 0
        return (self.states - 1) / span if span else 0.0, (self.bytes / span / 1e6) if span else 0.0


def run_config(args, name, case, overrides, publish, subscriber, extra):
    folder = os.path.join(args.out, name)
    shutil.rmtree(folder, ignore_errors=True)
    os.makedirs(folder)
    pub, ctl = "ipc://%s/pub.sock" % folder, "ipc://%s/ctl.sock" % folder
    argv = [args.surge, "run", case, "-o", os.path.join(folder, "out"), "--overwrite", "--threads", str(args.threads),
            "--control", ctl, "--paused", "-s", "output.snapshot_interval_s=0", "-s", "output.progress_interval_s=1e5",
            "-s", "time.end_s=%g" % args.end_s] + overrides + extra + (["--publish", pub] if publish else [])
    proc = subprocess.Popen(argv, stderr=subprocess.PIPE, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    sub = Subscriber(pub, subscriber == "stalled") if subscriber else None
    if sub:
        sub.start()
    time.sleep(1.0)  # the subscription reaches the publisher
    if proc.poll() is None:  # else it stopped at startup: its stderr says why
        surge_client.Control(ctl, 30).request({"cmd": "resume"})
    _, stderr = proc.communicate(timeout=1800)
    if sub:
        sub.done.set()
        sub.join(5)
    rate = re.findall(r"([0-9.]+) steps/s", stderr)
    if proc.returncode != 0 or not rate:
        cli_checks.fail("stream_bench", "%s failed (exit status %d):\n%s" % (" ".join(argv), proc.returncode, stderr))
    states_per_s, mbps = sub.rates() if sub and subscriber != "stalled" else (0.0, 0.0)
    return float(rate[-1]), states_per_s, mbps


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    parser.add_argument("--threads", type=cli_checks.positive_int, default=2)
    parser.add_argument("--end-s", type=cli_checks.positive, default=0.03,
                        help="simulated seconds per run (default 0.03)")
    parser.add_argument("--repeat", type=cli_checks.positive_int, default=3,
                        help="runs of each configuration (default 3)")
    parser.add_argument("--out", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "stream_bench"))
    args = parser.parse_args()
    film = os.path.join(ROOT, "cases", "incline_film.ini")
    tank = os.path.join(ROOT, "cases", "still_tank.ini")
    every = ["--publish-every", "1", "--publish-hz", "0"]
    configs = [
        ("alone", film, [], True, None, every),
        ("no-publish", film, [], False, None, []),
        ("fast-all", film, [], True, "fast", every),
        ("fast-30hz", film, [], True, "fast", []),
        ("stalled", film, [], True, "stalled", every),
        ("tank-alone", tank, ["-s", "time.end_s=%g" % (10 * args.end_s)], True, None, every),
        ("tank-fast-all", tank, ["-s", "time.end_s=%g" % (10 * args.end_s)], True, "fast", every),
    ]
    print("stream_bench: %s, %d solver thread(s), %s" % (time.strftime("%Y-%m-%d"), args.threads,
                                                         " ".join(sys.argv)))
    results = {name: [] for name, *_ in configs}
    for _ in range(args.repeat):
        for name, case, overrides, publish, subscriber, extra in configs:
            results[name].append(run_config(args, name, case, overrides, publish, subscriber, extra))
    print("%-14s %12s %8s %14s %10s" % ("config", "steps/s", "ratio", "states/s recv", "MB/s recv"))
    baseline = {}
    for name, case, *_ in configs:
        steps, states, mbps = (statistics.median(r[k] for r in results[name]) for k in range(3))
        scene = "tank" if case == tank else "film"
        baseline.setdefault(scene, steps)
        print("%-14s %12.1f %8.3f %14.1f %10.1f" % (name, steps, steps / baseline[scene], states, mbps))
    print("(medians of %d runs each; steps/s of every run: %s)" % (
        args.repeat, "; ".join("%s %s" % (n, " ".join("%.1f" % r[0] for r in rs)) for n, rs in results.items())))

if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
