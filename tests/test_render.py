#!/usr/bin/python3
"""Rendering through the surge program: frames and movies while it runs and from a finished run.

Usage: test_render.py SURGE_BINARY SOURCE_DIR WORK_DIR GROUP [SCHEME]
  SCHEME         explicit (the default) or implicit: the runs that share the common settings take
                 -s numerics.scheme=SCHEME.
  GROUP live     --frames and --movie during a run: one PNG per frame drawn, a movie with one frame per frame
                 due (ffprobe: count, size, duration), a rendered frame on the stream's "frame" topic, and the
                 solver's final state hash equal to the same run without rendering.
  GROUP ctrl_c   Ctrl-C in a terminal (SIGINT to the whole process group) during a run with --movie: surge stops,
                 and the movie holds every frame due, drawn or, where the renderer was busy, repeated (ffmpeg is in
                 its own process group, so it is not stopped halfway).
  GROUP restart  a rendering run killed hard after a periodic checkpoint, restarted into the same folders:
                 frames.csv lists each PNG once, in time order, on the frame cadence, without the frames the
                 killed run drew after its checkpoint.
  GROUP offline  `surge render RUN_DIR` turns the run's snapshots into as many PNG frames and movie frames; a
                 restarted run numbers its frames on, and its --movie starts with the first run's frames.
  GROUP inputs   bad rendering options get exit status 2 or 3 and a message naming the problem.

Each check prints "name: ok" or "name: FAILED ..."; exits 1 if any failed. Every command has a timeout.
"""
import json
import os
import re
import shutil
import signal
import struct
import subprocess
import sys
import time

import numpy as np

SURGE, SOURCE, WORK, GROUP = sys.argv[1:5]
from checks import check, finish  # noqa: E402
from surgepy import client as surge_client  # noqa: E402

TANK = os.path.join(SOURCE, "cases", "still_tank.ini")
COMMON = ["-s", "time.end_s=0.2", "-s", "render.width_px=640", "-s", "render.height_px=360",
          "-s", "render.frame_interval_s=0.02", "-s", "render.movie_fps=10", "-s", "output.snapshot_interval_s=0.05",
          "--threads", "1"] + (["-s", "numerics.scheme=" + sys.argv[5]] if len(sys.argv) > 5 else [])
ENV = dict(os.environ, OMP_WAIT_POLICY="PASSIVE")



def run(args, timeout=180):
    p = subprocess.run([SURGE] + args, capture_output=True, text=True, timeout=timeout, env=ENV)
    return p.returncode, p.stderr


def probe(path):
    p = subprocess.run(["ffprobe", "-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries",
                        "stream=nb_read_frames,width,height,codec_name:format=duration", "-of", "json", path],
                       capture_output=True, text=True, timeout=60)
    if p.returncode != 0:
        return None
    info = json.loads(p.stdout)
    stream = info["streams"][0]
    return (int(stream["nb_read_frames"]), stream["width"], stream["height"], float(info["format"]["duration"]),
            stream["codec_name"])


def state_hash(stderr):
    m = re.search(r"state hash ([0-9a-f]{16})", stderr)
    return m.group(1) if m else None


def fresh(name):
    d = os.path.join(WORK, name)
    shutil.rmtree(d, ignore_errors=True)
    os.makedirs(d)
    return d


def group_live():
    d = fresh("live")
    pub = "ipc://" + os.path.join(d, "pub.sock")
    ctl = "ipc://" + os.path.join(d, "ctl.sock")
    args = ["run", TANK, "-o", os.path.join(d, "out"), "--frames", os.path.join(d, "frames"),
            "--movie", os.path.join(d, "movie.mp4"), "--publish", pub, "--control", ctl, "--paused"] + COMMON
    proc = subprocess.Popen([SURGE] + args, stderr=subprocess.PIPE, text=True, env=ENV)
    sub = surge_client.subscribe(pub, ["frame"], latest_only=False)
    time.sleep(0.5)
    surge_client.Control(ctl, 10).request({"cmd": "resume"})
    frame = surge_client.receive(sub, 60000)
    _, stderr = proc.communicate(timeout=180)
    check("live: run with --frames and --movie finishes", proc.returncode == 0, stderr)
    m = re.search(r"rendered (\d+) of (\d+) frames due", stderr)
    drawn, due = (int(m.group(1)), int(m.group(2))) if m else (0, 0)
    check("live: 11 frames due over 0.2 s at 0.02 s, all reported", due == 11 and 0 < drawn <= due, stderr[-500:])
    frames = sorted(f for f in os.listdir(os.path.join(d, "frames")) if f.endswith(".png"))
    heads = [open(os.path.join(d, "frames", f), "rb").read(8) for f in frames]
    check("live: one PNG file per frame drawn", len(frames) == drawn and all(h == b"\x89PNG\r\n\x1a\n" for h in heads),
          "%d files, %d drawn" % (len(frames), drawn))
    info = probe(os.path.join(d, "movie.mp4"))
    check("live: the movie has one frame per frame due, the frame size, and due/fps seconds",
          info is not None and info[0] == due and info[1:3] == (640, 360) and abs(info[3] - due / 10) < 0.051,
          "ffprobe: %s, %d due" % (info, due))
    check("live: a rendered frame arrives on the stream's frame topic as a PNG",
          frame is not None and frame[0] == "frame" and bytes(frame[2]["png"][:8]) == b"\x89PNG\r\n\x1a\n",
          str(frame[1] if frame else None))
    code, plain = run(["run", TANK, "-o", os.path.join(d, "plain")] + COMMON)
    check("live: rendering does not change the solver's results (same state hash)",
          code == 0 and state_hash(plain) and state_hash(plain) == state_hash(stderr),
          "%s vs %s" % (state_hash(stderr), state_hash(plain)))


def children(pid):
    found = []
    for task in os.listdir("/proc/%d/task" % pid):
        with open("/proc/%d/task/%s/children" % (pid, task)) as f:
            found += [int(c) for c in f.read().split()]
    return found


def command_name(pid):
    try:
        with open("/proc/%d/comm" % pid) as f:
            return f.read().strip()
    except OSError:
        return ""


def group_ctrl_c():
    d = fresh("ctrl_c")
    frames = os.path.join(d, "frames")
    args = ["run", TANK, "-o", os.path.join(d, "out"), "--frames", frames, "--movie", os.path.join(d, "movie.mp4")]
    args += COMMON + ["-s", "time.end_s=100"]
    proc = subprocess.Popen([SURGE] + args, stderr=subprocess.PIPE, text=True, env=ENV, start_new_session=True)
    deadline = time.time() + 120
    while time.time() < deadline and proc.poll() is None and \
            len([f for f in os.listdir(frames) if f.endswith(".png")] if os.path.isdir(frames) else []) < 4:
        time.sleep(0.1)
    ffmpeg_groups = [os.getpgid(pid) for pid in children(proc.pid) if command_name(pid) == "ffmpeg"]
    check("ctrl_c: ffmpeg runs in a process group of its own", len(ffmpeg_groups) == 1 and
          ffmpeg_groups[0] != os.getpgid(proc.pid), "ffmpeg groups %s, surge's %d" % (ffmpeg_groups, proc.pid))
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, stderr = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        _, stderr = proc.communicate()
    check("ctrl_c: SIGINT to the process group stops the run (exit status 4)", proc.returncode == 4,
          "exit %s: %s" % (proc.returncode, stderr[-500:]))
    m = re.search(r"rendered (\d+) of (\d+) frames due", stderr)
    drawn, due = (int(m.group(1)), int(m.group(2))) if m else (0, 0)
    info = probe(os.path.join(d, "movie.mp4"))
    # a frame skipped while the renderer was busy repeats the previous image in the movie, which keeps time
    # (surge/render.h): the movie holds every frame due, not only those drawn
    check("ctrl_c: the movie holds every frame due (at least 4 drawn)", drawn >= 4 and info is not None and
          info[0] == due, "ffprobe: %s, %d drawn of %d due; %s" % (info, drawn, due, stderr[-300:]))


def checkpoint_time_s(path):
    with open(path, "rb") as f:
        head = f.read(24)
        f.seek(24 + struct.unpack("<Q", head[16:24])[0] + 8)
        return struct.unpack("<d", f.read(8))[0]


def frame_rows(frames):
    path = os.path.join(frames, "frames.csv")
    if not os.path.exists(path):
        return []
    with open(path) as f:
        lines = [line.split(",") for line in f.read().splitlines()[1:] if line]
    return [(int(a), int(b), float(c)) for a, b, c in lines if c]


def group_restart():
    d = fresh("restart")
    out, frames = os.path.join(d, "out"), os.path.join(d, "frames")
    interval = 0.005
    cadence = ["-s", "render.frame_interval_s=%g" % interval, "-s", "render.width_px=320", "-s", "render.height_px=180",
               "-s", "output.checkpoint_interval_s=0.05", "--threads", "1"]
    proc = subprocess.Popen([SURGE, "run", TANK, "-o", out, "--frames", frames, "-s", "time.end_s=100"] + cadence,
                            stderr=subprocess.DEVNULL, env=ENV)
    checkpoint = os.path.join(out, "checkpoint.bin")
    deadline, killed_after = time.time() + 120, []
    while time.time() < deadline and proc.poll() is None:
        if os.path.exists(checkpoint):
            t_ck = checkpoint_time_s(checkpoint)
            killed_after = [r for r in frame_rows(frames) if r[2] > t_ck + 2 * interval]
            if killed_after:
                break
        time.sleep(0.05)
    proc.kill()
    proc.wait()
    t_ck = checkpoint_time_s(checkpoint) if os.path.exists(checkpoint) else None
    after = [r for r in frame_rows(frames) if t_ck is not None and r[2] > t_ck]
    check("restart: the killed run drew frames after its last checkpoint (the case under test)", bool(after),
          "checkpoint at %s, rows %s" % (t_ck, frame_rows(frames)[-5:]))
    code, stderr = run(["run", "--restart", checkpoint, "--frames", frames, "-s",
                        "time.end_s=%.9g" % ((t_ck or 0) + 0.03)] + cadence[-2:])
    rows = frame_rows(frames)
    times = [t for _, _, t in rows]
    numbers = [n for n, _, _ in rows]
    pngs = sorted(int(f[6:-4]) for f in os.listdir(frames) if f.startswith("frame_") and f.endswith(".png"))
    slots = [int(t / interval + 1e-9) for t in times]  # a frame is drawn at the first step past each multiple
    check("restart: frames.csv in time order, each PNG listed once, numbers increasing, one frame per interval",
          code == 0 and len(rows) > len(after) and all(b > a for a, b in zip(slots, slots[1:])) and
          all(b > a for a, b in zip(numbers, numbers[1:])) and pngs == numbers,
          "exit %d; times %s; numbers %s; PNGs %s\n%s" % (code, times, numbers, pngs, stderr[-300:]))


def group_offline():
    d = fresh("offline")
    code, stderr = run(["run", TANK, "-o", os.path.join(d, "out")] + COMMON)
    snapshots = [f for f in os.listdir(os.path.join(d, "out")) if f.startswith("snap_")]
    code2, stderr2 = run(["render", os.path.join(d, "out"), "--movie", os.path.join(d, "movie.mp4"),
                          "--frames", os.path.join(d, "frames"), "-s", "render.field=pressure", "-s",
                          "render.view=fixed", "-s", "render.view_x0_m=0", "-s", "render.view_x1_m=0.2"])
    frames = [f for f in os.listdir(os.path.join(d, "frames")) if f.endswith(".png")] \
        if os.path.isdir(os.path.join(d, "frames")) else []
    info = probe(os.path.join(d, "movie.mp4"))
    check("offline: surge render makes one frame and one movie frame per snapshot",
          code == 0 and code2 == 0 and len(snapshots) == 5 and len(frames) == 5 and info and info[0] == 5,
          "%d snapshots, %d frames, ffprobe %s\n%s" % (len(snapshots), len(frames), info, stderr2))
    rows = frame_rows(os.path.join(d, "frames"))
    check("offline: frames.csv lists each frame with its step and time, as a live run's does",
          [r[0] for r in rows] == list(range(5)) and all(b[1] > a[1] and b[2] > a[2] for a, b in zip(rows, rows[1:])),
          str(rows))
    code3, stderr3 = run(["render", os.path.join(d, "out")])
    check("offline: without --frames or --movie the frames go to RUN_DIR/frames",
          code3 == 0 and len([f for f in os.listdir(os.path.join(d, "out", "frames")) if f.endswith(".png")]) == 5,
          stderr3)
    # render.frame_interval_s on the command line: one snapshot per interval (snapshots every 0.05 s, 0 to 0.2 s)
    code9, stderr9 = run(["render", os.path.join(d, "out"), "--frames", os.path.join(d, "sparse_frames"), "-s",
                          "render.frame_interval_s=0.1"])
    sparse = [f for f in os.listdir(os.path.join(d, "sparse_frames")) if f.endswith(".png")] if code9 == 0 else []
    check("offline: with -s render.frame_interval_s=0.1 one frame per 0.1 s of the 0.05 s snapshots",
          code9 == 0 and len(sparse) == 3 and "rendered 3 snapshots" in stderr9, "%s\n%s" % (sparse, stderr9[-300:]))
    code10, stderr10 = run(["render", os.path.join(d, "out"), "--frames", os.path.join(d, "sparse_frames2"), "-s",
                            " render.frame_interval_s = 0.1"])
    check("offline: the same with spaces around the name, as -s allows them", code10 == 0 and
          "rendered 3 snapshots" in stderr10, stderr10[-300:])
    # one colour range for the whole movie, from all its frames, unless the user sets one
    check("offline: an automatic colour range is the range over all frames", "over all 5 frames" in stderr3,
          stderr3[-300:])

    # a restarted run adds its frames after the first run's instead of overwriting them
    cont_run, cont_frames = os.path.join(d, "cont"), os.path.join(d, "cont_frames")
    code6, stderr6 = run(["run", TANK, "-o", cont_run, "--frames", cont_frames] + COMMON[2:] + ["-s", "time.end_s=0.1"])
    first = sorted(f for f in os.listdir(cont_frames) if f.endswith(".png")) if code6 == 0 else []
    first_bytes = [open(os.path.join(cont_frames, f), "rb").read() for f in first]
    cont_movie = os.path.join(d, "cont.mp4")
    code7, stderr7 = run(["run", "--restart", os.path.join(cont_run, "checkpoint.bin"), "--frames", cont_frames,
                          "--movie", cont_movie, "-s", "time.end_s=0.2", "-s", "output.progress_interval_s=0"])
    after = sorted(f for f in os.listdir(cont_frames) if f.endswith(".png")) if code7 == 0 else []
    kept = after[:len(first)] == first and all(open(os.path.join(cont_frames, f), "rb").read() == b
                                               for f, b in zip(first, first_bytes))
    # the renderer skips a frame it is too busy to draw (by design), so on a loaded machine either run may have
    # fewer than its 5 frames due: the test asks only that the restarted run adds frames after the first run's
    new_names = after[len(first):]
    check("offline: a restarted run numbers its frames on after the first run's, which stay as they were",
          code6 == 0 and code7 == 0 and len(first) >= 1 and len(new_names) >= 1 and kept and
          min(new_names) > max(first),
          "first run %d frames, after the restart %d: %s\n%s%s" % (len(first), len(after), after[-3:], stderr6[-300:],
                                                                  stderr7[-300:]))

    info = probe(cont_movie)
    # one movie frame per frame number: a number skipped while the renderer was busy repeats the previous image in
    # the movie, so that it keeps simulated time (without skips, one movie frame per PNG)
    def span(names):
        numbers = [int(name[len("frame_"):-len(".png")]) for name in names]
        return max(numbers) - min(numbers) + 1 if numbers else 0
    check("offline: the restarted run's movie starts with the first run's frames: one movie frame per frame number",
          code7 == 0 and info is not None and info[0] == span(after) and
          "(%d of them drawn before the restart)" % span(first) in stderr7,
          "%d PNGs spanning %d frame numbers, ffprobe %s\n%s" % (len(after), span(after), info, stderr7[-400:]))
    # damage the first run's last frame (on a busy machine it may have drawn fewer than the 3 frames due)
    damaged = first[-1] if first else "frame_missing.png"
    with open(os.path.join(cont_frames, damaged), "wb") as f:
        f.write(b"not a PNG")
    code8, stderr8 = run(["run", "--restart", os.path.join(cont_run, "checkpoint.bin"), "--frames", cont_frames,
                          "--movie", os.path.join(d, "cont2.mp4"), "-s", "time.end_s=0.3"])
    check("offline: a damaged frame before the restart: refused at start, naming it, and no movie written",
          code8 == 2 and len(first) >= 1 and damaged in stderr8 and "Not a PNG" in stderr8 and
          not os.path.exists(os.path.join(d, "cont2.mp4")), "exit %d\n%s" % (code8, stderr8[-400:]))

    # a run with a disc: offline frames draw it as a solid disc in the boulder colour with its spoke, which needs the
    # boulders_*.vtp written next to each snapshot (the spoke's colour, 235 grey, is used for nothing else)
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.image
    disc_run = os.path.join(d, "disc")
    code4, stderr4 = run(["run", os.path.join(SOURCE, "cases", "boulder_couette.ini"), "-o", disc_run, "-s",
                          "time.end_s=0.001", "-s", "output.progress_interval_s=0"])
    code5, stderr5 = run(["render", disc_run, "--frames", os.path.join(d, "disc_frames")])
    frames = sorted(f for f in os.listdir(os.path.join(d, "disc_frames")) if f.endswith(".png")) if code5 == 0 else []
    rgb = (matplotlib.image.imread(os.path.join(d, "disc_frames", frames[-1]))[..., :3] * 255).round() if frames else None
    mark = int(np.count_nonzero((rgb == [235, 235, 235]).all(-1))) if frames else 0
    disc = int(np.count_nonzero((rgb == [95, 80, 70]).all(-1))) if frames else 0
    check("offline: a disc is drawn in the boulder colour with its spoke",
          code4 == 0 and code5 == 0 and mark > 10 and disc > 1000,
          "mark pixels %d, boulder pixels %d\n%s%s" % (mark, disc, stderr4[-300:], stderr5[-300:]))


def group_inputs():
    d = fresh("inputs")
    out = os.path.join(d, "out")
    cases = [
        (["run", TANK, "-o", out, "--frames", "/proc/surge_no_such_dir"], (2,), "/proc/surge_no_such_dir"),
        (["run", TANK, "-o", out, "--movie", os.path.join(d, "missing", "m.mp4")], (2,), "m.mp4"),
        (["run", TANK, "-o", out, "--frames"], (2,), "--frames needs a folder"),
        (["run", TANK, "-o", out, "--frames", d, "-s", "render.width_px=100000"], (2,), "render.width_px"),
        (["run", TANK, "-o", out, "--frames", d, "-s", "render.field=temperature"], (2,), "render.field"),
        (["run", TANK, "-o", out, "--frames", d, "-s", "render.view_x1_m=-1"], (2,), "render.view_x1_m"),
        (["run", TANK, "-o", out, "--frames", d, "--font", "/nonexistent.ttf"], (2,), "/nonexistent.ttf"),
        (["render", os.path.join(d, "nothing_here")], (2,), "params.ini"),
        (["render"], (2,), "render needs a RUN_DIR"),
        (["render", d, "--publish", "5555"], (2,), "render takes only"),
        (["render", d, "-o", out], (2,), "render takes only"),
        (["render", d, "-s", "numerics.dp_m=0.01"], (2,), "'-s numerics.dp_m=0.01': only render.key=value"),
    ]
    wrong = []
    for args, codes, words in cases:
        code, stderr = run(args[:2] + ["-s", "time.end_s=0.001"] + args[2:] if args[0] == "run" else args, timeout=60)
        if code not in codes or words not in stderr:
            wrong.append("%s -> exit %d: %s" % (" ".join(args), code, stderr.strip()[-300:]))
    check("inputs: bad rendering options exit 2 with a message naming them (%d cases)" % len(cases), not wrong,
          "\n".join(wrong))

    # no ffmpeg on PATH: a clear error, and a movie already there is left as it was
    movie = os.path.join(d, "kept.mp4")
    with open(movie, "wb") as f:
        f.write(b"an earlier movie")
    p = subprocess.run([SURGE, "run", TANK, "-o", out, "--overwrite", "-s", "time.end_s=0.001", "--movie", movie],
                       capture_output=True, text=True, timeout=60, env=dict(ENV, PATH="/nonexistent"))
    with open(movie, "rb") as f:
        kept = f.read()
    check("inputs: without ffmpeg, --movie exits 2 naming ffmpeg and leaves the existing movie untouched",
          p.returncode == 2 and "ffmpeg" in p.stderr and kept == b"an earlier movie",
          "exit %d, file %r: %s" % (p.returncode, kept[:40], p.stderr.strip()[-300:]))

    # a snapshot whose array offset points far outside the file is refused, naming the file and the array
    run_dir = os.path.join(d, "corrupt")
    code, stderr = run(["run", TANK, "-o", run_dir, "-s", "time.end_s=0.001"], timeout=60)
    snapshots = sorted(f for f in os.listdir(run_dir) if f.startswith("snap_")) if code == 0 else []
    if snapshots:
        path = os.path.join(run_dir, snapshots[-1])
        with open(path, "rb") as f:
            data = f.read()
        with open(path, "wb") as f:
            f.write(data.replace(b'offset="0"', b'offset="18446744073709551615"', 1))
    code, stderr = run(["render", run_dir], timeout=60)
    check("inputs: a snapshot with an array offset beyond the file exits 2 naming it",
          bool(snapshots) and code == 2 and snapshots[-1] in stderr and "truncated or has the wrong size" in stderr,
          "exit %d: %s" % (code, stderr.strip()[-300:]))

    # run.pvd naming a folder instead of a snapshot (it sent the reader to malloc 2^63 bytes)
    if snapshots:
        os.remove(path)
        os.makedirs(path)
    code, stderr = run(["render", run_dir, "--overwrite"], timeout=60)
    check("inputs: a run.pvd entry naming a folder exits 2, naming it",
          bool(snapshots) and code == 2 and snapshots[-1] in stderr and "not a regular file" in stderr,
          "exit %d: %s" % (code, stderr.strip()[-300:]))


os.makedirs(WORK, exist_ok=True)
{"live": group_live, "ctrl_c": group_ctrl_c, "restart": group_restart, "offline": group_offline,
 "inputs": group_inputs}[GROUP]()
sys.exit(finish())
