#!/usr/bin/python3
"""surge_watch: subscribes to a running surge (started with --publish) and shows or records its state.

  surge_watch.py                                  live window: particles coloured by speed, updating
  surge_watch.py --field vx_rel                   colour by x velocity relative to the belt
  surge_watch.py --png live.png                   no display: rewrite live.png with the newest state
  surge_watch.py --record rec --count 100         save 100 states as rec/state_<step>.npz, stats in rec/stats.jsonl

It always shows the newest state: older messages queued meanwhile are skipped (the publisher never waits for
this client). It stops when the run ends (stats status "final"), after --count states or --duration seconds.
"""
import argparse
import json
import os
import sys
import time

import zmq

from surgepy import cli_checks
from surgepy import client as surge_client

FIELDS = {  # colour field: (label, unit, state fields needed)
    "speed": ("speed", "m/s", ["vx_mps", "vy_mps"]),
    "vx": ("x velocity", "m/s", ["vx_mps"]),
    "vx_rel": ("x velocity relative to the belt", "m/s", ["vx_mps"]),
    "vy": ("y velocity", "m/s", ["vy_mps"]),
    "pressure": ("pressure", "Pa", ["pressure_pa"]),
    "density": ("density", "kg/m^3", ["density_kgpm3"]),
}


def colour_values(field, arrays, stats):
    import numpy as np
    if field == "speed":
        return np.hypot(arrays["vx_mps"], arrays["vy_mps"])
    if field == "vx_rel":
        return arrays["vx_mps"] - (stats or {}).get("belt_speed_mps", 0.0)
    return arrays[{"vx": "vx_mps", "vy": "vy_mps", "pressure": "pressure_pa", "density": "density_kgpm3"}[field]]


class View:
    """A scatter plot of the particles (fluid coloured, walls grey) redrawn for each new state."""

    def __init__(self, field, interactive):
        import matplotlib
        if not interactive:
            matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        self.plt, self.field = plt, field
        self.fig, self.ax = plt.subplots(figsize=(12, 4))
        self.colorbar = None
        if interactive:
            plt.ion()
            plt.show(block=False)

    def draw(self, header, arrays, stats):
        ax = self.ax
        ax.clear()
        fluid = arrays["kind"] == 0
        values = colour_values(self.field, arrays, stats)
        ax.scatter(arrays["x_m"][~fluid], arrays["y_m"][~fluid], s=1, c="0.6", linewidths=0)
        points = ax.scatter(arrays["x_m"][fluid], arrays["y_m"][fluid], s=2, c=values[fluid], cmap="viridis",
                            linewidths=0)
        label, unit, _ = FIELDS[self.field]
        if self.colorbar is None:
            self.colorbar = self.fig.colorbar(points, ax=ax)
        else:
            self.colorbar.update_normal(points)
        self.colorbar.set_label("%s (%s)" % (label, unit))
        ax.set_aspect("equal")
        ax.set_xlabel("x along the bed (m)")
        ax.set_ylabel("y normal to the bed (m)")
        ax.set_title("t = %.3f s, step %d, %d particles" % (header["time_s"], header["step"], header["count"]))

    def show(self):
        self.fig.canvas.draw_idle()
        self.plt.pause(0.01)

    def save(self, path):
        self.fig.savefig(path + ".tmp.png", dpi=100)
        os.replace(path + ".tmp.png", path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-e", "--endpoint", type=cli_checks.endpoint, default="tcp://127.0.0.1:5555",
                        help="surge's publisher (default tcp://127.0.0.1:5555; a bare port means loopback)")
    cli_checks.add_curve_options(parser)
    parser.add_argument("--field", choices=sorted(FIELDS), default="speed", help="colour field (default speed)")
    parser.add_argument("--png", type=cli_checks.png_file,
                        help="no window: rewrite this PNG with the newest state (at most twice a second)")
    parser.add_argument("--record", metavar="DIR", type=cli_checks.folder,
                        help="save every state received (all fields) and the stats")
    parser.add_argument("--count", type=int, default=0, help="stop after this many states (0: no limit)")
    parser.add_argument("--duration", type=cli_checks.positive, help="stop after this many seconds (default: no limit)")
    args = parser.parse_args()
    if args.count < 0:
        parser.error("--count must be >= 0")
    interactive = not args.png and not args.record
    if interactive and not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        parser.error("no display: use --png FILE or --record DIR")

    import numpy as np
    fields = ["x_m", "y_m", "kind"] + FIELDS[args.field][2]
    state_topic = "state" if args.record else "state/" + ",".join(fields)  # every field when recording
    try:
        sub = surge_client.subscribe(args.endpoint, [state_topic, "stats"], latest_only=not args.record,
                                     curve=cli_checks.curve_of(parser, args))
    except zmq.ZMQError as e:
        parser.error("--endpoint %s: %s" % (args.endpoint, e))
    stats_log = None
    if args.record:
        os.makedirs(args.record, exist_ok=True)
        stats_log = open(os.path.join(args.record, "stats.jsonl"), "w")
    print("surge_watch: waiting for surge's states from %s" % args.endpoint, file=sys.stderr, flush=True)
    view = View(args.field, interactive) if not args.record else None
    start, states, stats, last_png = time.time(), 0, None, 0.0
    while True:
        if args.duration and time.time() - start > args.duration:
            break
        try:
            if args.record:
                message = surge_client.receive(sub, 200)
                latest = {message[0]: message[1:]} if message else {}
            else:
                latest = surge_client.receive_latest(sub, 200)
            if not args.record and state_topic in latest and not set(fields) <= set(latest[state_topic][1]):
                raise surge_client.ProtocolError("a state without the fields %s" % ", ".join(fields))
        except surge_client.ProtocolError as e:
            cli_checks.fail("surge_watch", "bad message from %s: %s" % (args.endpoint, e))
        except KeyboardInterrupt:
            break
        if "stats" in latest:
            stats = latest["stats"][0]
            if stats_log:
                stats_log.write(json.dumps(stats) + "\n")
        if state_topic in latest:
            header, arrays = latest[state_topic]
            states += 1
            if args.record:
                np.savez(os.path.join(args.record, "state_%09d.npz" % header["step"]),
                         header=json.dumps(header), **arrays)
            elif args.png and time.time() - last_png >= 0.5:
                view.draw(header, arrays, stats)
                view.save(args.png)
                last_png = time.time()
            elif interactive:
                view.draw(header, arrays, stats)
                view.show()
        if (args.count and states >= args.count) or (stats and stats.get("status") == "final"):
            break
    if stats_log:
        stats_log.close()
    print("surge_watch: %d states received%s" % (states, ", run finished" if stats and stats.get("status") == "final"
                                                  else ""), file=sys.stderr)
    if states == 0:  # nothing came: no run there, or the wrong endpoint; not a success
        print("surge_watch: no state received from %s (is a run publishing there? surge run --publish PORT)"
              % args.endpoint, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
