#!/usr/bin/python3
"""render_bench: the renderer's frames per second, and the solver's slowdown while it renders.

  bench/render_bench.py [--surge build/surge] [--threads 2] [--end-s 0.03] [--repeat 3] [--out runs/render_bench]

1. build/surge-render-bench 1920 1080: frames per second drawing 20,000 and 200,000 particles at 1920 x 1080,
   with and without PNG encoding.
2. The benchmark scene (cases/incline_film.ini, 20,000 fluid particles) for --end-s of simulated time, without
   rendering and with --frames and --movie at 1920 x 1080 every render.frame_interval_s = 0.0005 s (about one
   frame per 11 steps), run in turn --repeat times. Prints the median solver steps/s of each, their ratio, and
   how many of the frames due the renderer drew (it skips what it cannot keep up with; it never holds back the
   solver).
"""
import argparse
import os
import re
import shutil
import statistics
import subprocess
import sys
import time

from surgepy import cli_checks

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def fail(message):
    cli_checks.fail("render_bench", message)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--surge", type=cli_checks.executable, default=os.path.join(ROOT, "build", "surge"))
    parser.add_argument("--threads", type=cli_checks.positive_int, default=2)
    parser.add_argument("--end-s", type=cli_checks.positive, default=0.03)
    parser.add_argument("--repeat", type=cli_checks.positive_int, default=3)
    parser.add_argument("--out", type=cli_checks.folder, default=os.path.join(ROOT, "runs", "render_bench"))
    args = parser.parse_args()
    bench = os.path.join(os.path.dirname(args.surge), "surge-render-bench")
    if not (os.path.isfile(bench) and os.access(bench, os.X_OK)):
        fail("%s: not an executable (it is built next to surge)" % bench)
    print("render_bench: %s, %s" % (time.strftime("%Y-%m-%d"), " ".join(sys.argv)), flush=True)
    if subprocess.run([bench, "1920", "1080", "20"]).returncode != 0:
        fail("%s failed" % bench)

    film = os.path.join(ROOT, "cases", "incline_film.ini")
    common = ["--threads", str(args.threads), "-s", "time.end_s=%g" % args.end_s, "-s", "output.snapshot_interval_s=0",
              "-s", "output.progress_interval_s=1e5"]
    render = ["-s", "render.width_px=1920", "-s", "render.height_px=1080", "-s", "render.frame_interval_s=0.0005"]
    rates = {"solver alone": [], "rendering": []}
    drawn = []
    for _ in range(args.repeat):
        for name in rates:
            folder = os.path.join(args.out, name.replace(" ", "_"))
            shutil.rmtree(folder, ignore_errors=True)
            os.makedirs(folder)  # the movie's folder must exist
            extra = render + ["--frames", os.path.join(folder, "frames"), "--movie",
                              os.path.join(folder, "movie.mp4")] if name == "rendering" else []
            p = subprocess.run([args.surge, "run", film, "-o", os.path.join(folder, "out"), "--overwrite"] + common + extra,
                               capture_output=True, text=True, env=dict(os.environ, OMP_WAIT_POLICY="PASSIVE"))
            rate = re.findall(r"([0-9.]+) steps/s", p.stderr)
            if p.returncode != 0 or not rate:
                fail("%s failed (exit status %d):\n%s" % (name, p.returncode, p.stderr))
            rates[name].append(float(rate[-1]))
            m = re.search(r"rendered (\d+) of (\d+) frames due.*?([0-9.]+) ms per frame drawing, ([0-9.]+) ms encoding",
                          p.stderr)
            if m:
                drawn.append(m.groups())
    alone, rendering = statistics.median(rates["solver alone"]), statistics.median(rates["rendering"])
    print("incline film, %d solver thread(s): %.1f steps/s alone, %.1f steps/s while rendering (ratio %.3f)"
          % (args.threads, alone, rendering, rendering / alone))
    print("frames drawn/due per run, ms drawing, ms encoding (PNG + movie): %s"
          % "; ".join("%s/%s, %s, %s" % d for d in drawn))
    print("steps/s of every run: %s" % "; ".join("%s %s" % (n, " ".join("%.1f" % r for r in rs))
                                                  for n, rs in rates.items()))


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
