#!/usr/bin/python3
"""The solver's step rate while clients flood its control socket (docs/verification.md, "Control floods").

Usage: control_flood.py [SURGE_BINARY] [--seconds S] [--clients N] [--repeat R] [--curve]

Starts `SURGE run cases/still_tank.ini --threads 1 --control tcp://127.0.0.1:PORT` (no other output) and measures
its steps per second with N clients (processes, default 4) each keeping 8 requests in flight on a DEALER socket,
for each kind of request in turn, each flood between two phases with nothing else connected: its ratio is to the
mean of those two idle rates (A B A B ..., the machine's drift cancelled), over --repeat rounds. Each rate is the
step count from two `status` requests S seconds apart (default 4). Traffic goes to 127.0.0.1 only and
every phase is bounded in time. Prints one row per kind of request: the median ratio and its range, and the
replies per second the flooding clients received. With --curve the run and every client
use ZeroMQ's CURVE (keys made with `surge keygen` in a temporary folder; the clients' key is the one admitted).
"""
import argparse
import json
import multiprocessing
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time

import zmq

from surgepy import client as surge_client

SOURCE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IN_FLIGHT = 8
KINDS = [
    ("status", b'{"cmd": "status"}'),
    ("get", b'{"cmd": "get", "key": "fluid.viscosity_m2ps"}'),
    ("list", b'{"cmd": "list"}'),
    ("bad JSON", b'{"cmd": "status", '),
    ("junk 6 kB", bytes((i * 7919) % 251 for i in range(6000))),
    ("junk 60 kB", bytes((i * 7919) % 251 for i in range(60000))),
]


def secure(sock, curve):
    if curve is not None:
        sock.curve_serverkey, sock.curve_publickey, sock.curve_secretkey = curve


def flood(endpoint, request, seconds, replies, curve):
    """One client: IN_FLIGHT requests outstanding, a new one sent for each reply (IN_FLIGHT more after 0.1 s
    without one), until seconds have passed."""
    ctx = zmq.Context()
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 0)
    secure(s, curve)
    s.connect(endpoint)
    for _ in range(IN_FLIGHT):
        s.send(request)
    received, end = 0, time.time() + seconds
    while time.time() < end:
        if s.poll(100):
            s.recv()
            received += 1
            s.send(request, zmq.DONTWAIT)
        else:  # no reply (a request over the size limit closes the connection): send again
            for _ in range(IN_FLIGHT):
                try:
                    s.send(request, zmq.DONTWAIT)
                except zmq.Again:
                    break
    with replies.get_lock():
        replies.value += received
    s.close()
    ctx.term()


def steps(control):
    control.send(b'{"cmd": "status"}')
    if not control.poll(30000):
        raise SystemExit("no reply to status within 30 s")
    return json.loads(control.recv())["step"]


def measure(control, seconds):
    a, t0 = steps(control), time.time()
    time.sleep(seconds)
    b, t1 = steps(control), time.time()
    return (b - a) / (t1 - t0)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("surge", nargs="?", default=os.path.join(SOURCE, "build", "surge"))
    ap.add_argument("--seconds", type=float, default=4.0)
    ap.add_argument("--clients", type=int, default=4)
    ap.add_argument("--curve", action="store_true", help="the run and the clients use CURVE")
    ap.add_argument("--repeat", type=int, default=3, help="rounds of every flood (default 3)")
    args = ap.parse_args()
    keys_dir = tempfile.mkdtemp(prefix="surge_flood_keys_")
    curve, secured = None, []
    if args.curve:
        for name in ("run", "client"):
            subprocess.run([args.surge, "keygen", os.path.join(keys_dir, name)], check=True,
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        curve = surge_client.curve_keys(os.path.join(keys_dir, "run.pub"), os.path.join(keys_dir, "client.key"))
        secured = ["--curve-key", os.path.join(keys_dir, "run.key"), "--curve-clients",
                   os.path.join(keys_dir, "client.pub")]
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    endpoint = "tcp://127.0.0.1:%d" % probe.getsockname()[1]
    probe.close()
    run = subprocess.Popen([args.surge, "run", os.path.join(SOURCE, "cases", "still_tank.ini"), "--threads", "1",
                            "-o", "/tmp/surge_control_flood", "--overwrite", "-s", "time.end_s=1e6", "-s",
                            "output.snapshot_interval_s=0", "-s", "output.checkpoint_interval_s=0", "-s",
                            "output.diagnostics_interval_s=0", "-s", "output.progress_interval_s=0",
                            "--control", endpoint] + secured, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                           env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
    ctx = zmq.Context()
    control = ctx.socket(zmq.REQ)
    control.setsockopt(zmq.LINGER, 0)
    secure(control, curve)
    control.connect(endpoint)
    try:
        steps(control)
        time.sleep(1.0)  # the first steps' start-up out of the way
        # each flood between two idle phases, A B A B ..., so that a ratio compares rates measured seconds apart on
        # a machine whose speed drifts; --repeat rounds, the medians printed
        results = {name: [] for name, _ in KINDS}
        replied = {name: [] for name, _ in KINDS}
        idle_rates = []
        before = measure(control, args.seconds)
        idle_rates.append(before)
        for _ in range(args.repeat):
            for name, request in KINDS:
                replies = multiprocessing.Value("q", 0)
                clients = [multiprocessing.Process(target=flood, args=(endpoint, request, args.seconds + 2, replies,
                                                                       curve)) for _ in range(args.clients)]
                for c in clients:
                    c.start()
                time.sleep(0.5)
                rate = measure(control, args.seconds)
                for c in clients:
                    c.join(args.seconds + 30)
                    if c.is_alive():
                        c.kill()
                time.sleep(0.5)
                after = measure(control, args.seconds)
                idle_rates.append(after)
                results[name].append(rate / (0.5 * (before + after)))
                replied[name].append(replies.value / (args.seconds + 2))
                before = after
    finally:
        control.send(b'{"cmd": "stop"}')
        control.poll(10000)
        control.close()
        ctx.term()
        try:
            run.wait(30)
        except subprocess.TimeoutExpired:
            run.kill()
        shutil.rmtree(keys_dir, ignore_errors=True)
    print("%s, %d flooding clients, %d requests in flight each, %.0f s per phase, %d rounds%s" %
          (args.surge, args.clients, IN_FLIGHT, args.seconds, args.repeat, ", CURVE" if args.curve else ""))
    print("idle steps/s: median %.0f (%.0f to %.0f)" % (statistics.median(idle_rates), min(idle_rates),
                                                        max(idle_rates)))
    print("| requests | steps/s of the idle phases beside it: median (range) | replies/s to the flood |")
    print("|---|---|---|")
    for name, _ in KINDS:
        r = results[name]
        print("| %s | %.0f %% (%.0f-%.0f %%) | %.0f |" % (name, 100 * statistics.median(r), 100 * min(r), 100 * max(r),
                                                      statistics.median(replied[name])))
    return 0


if __name__ == "__main__":
    sys.exit(main())
