#!/usr/bin/python3
"""Every `#pragma omp simd` loop of the solver vectorises with AVX2, the instruction set of every x86-64 machine of the
last decade (some have AVX-512 as well).

Usage: test_vectorised_loops.py CC SOURCE_DIR INCLUDE_DIRS COMPILE_OPTIONS
  CC: GCC (the report read is GCC's -fopt-info-vec; tests/CMakeLists.txt adds the test only for GCC)
  INCLUDE_DIRS and COMPILE_OPTIONS: the solver library's (surge_sim's), as CMake lists (';'-separated)

Each source file of sim/src with such a loop is compiled as the library is (-O3, -fopenmp, its include directories
and options) but for -march=x86-64-v3 (AVX2, FMA), with GCC's vectoriser report. A loop passes when the report says
"loop vectorized" at the loop's place (GCC names a loop by a column of the pragma's line, the `for` line or the line
after it) and never "couldn't vectorize loop" at that place: a loop inlined into several callers is reported once
per copy, and every copy must be vectorised. The build's -fno-trapping-math is what lets the pair loops vectorise with
AVX2 alone: without it they vectorise only where AVX-512's masks can if-convert their conditional arithmetic, GCC says
"control flow in loop" on AVX2 and runs them scalar (the flag alone made them 2.2-3.2 times faster on a Zen 3 machine; docs/performance.md, "How the
pair loops are built, and what each part gains"), and this test fails for the fluid and wall pair loops.

Not a timing test: it checks what the compiler made of the loops, not how fast they ran.
"""
import glob
import os
import re
import subprocess
import sys
import tempfile

from checks import check, finish

CC, SOURCE = sys.argv[1:3]
INCLUDES = [d for d in sys.argv[3].split(";") if d]
OPTIONS = [o for o in sys.argv[4].split(";") if o and not o.startswith("-march=")]

REPORT = re.compile(r"^(?:.*/)?([\w.]+\.c):(\d+):(\d+): (optimized: loop vectorized|missed: couldn't vectorize loop)")
PRAGMA = re.compile(r"^\s*#pragma omp simd\b")

sources = sorted(glob.glob(os.path.join(SOURCE, "sim", "src", "**", "*.c"), recursive=True))
loops = 0
for path in sources:
    with open(path) as f:
        lines = f.read().split("\n")
    pragma_lines = [n + 1 for n, text in enumerate(lines) if PRAGMA.match(text)]
    if not pragma_lines:
        continue
    name = os.path.basename(path)
    with tempfile.TemporaryDirectory() as work:
        report_path = os.path.join(work, "report.txt")
        command = [CC, "-O3", "-std=c11", "-fopenmp", "-march=x86-64-v3"] + OPTIONS + \
                  ["-I" + d for d in INCLUDES] + ["-fopt-info-vec-all=" + report_path, "-c", path,
                                                  "-o", os.path.join(work, "out.o")]
        result = subprocess.run(command, capture_output=True, text=True)
        if not check("%s compiles for AVX2 (x86-64-v3)" % name, result.returncode == 0,
                     " ".join(command) + "\n" + result.stderr[-2000:]):
            continue
        with open(report_path) as f:
            report = f.read().split("\n")
    verdicts = {}  # (line, column) -> ["optimized" | "missed", ...]
    for text in report:
        m = REPORT.match(text)
        if m and m.group(1) == name:
            verdicts.setdefault((int(m.group(2)), int(m.group(3))), []).append(m.group(4).split(":")[0])
    for pragma in pragma_lines:
        loop_line = pragma + 1
        # GCC names a loop by a place on the pragma's line, the `for` line or the body's first line; the loop's place
        # is where it says either verdict the most times, and every verdict there must be "vectorized"
        places = {place: said for place, said in verdicts.items() if pragma <= place[0] <= pragma + 2}
        place = max(places, key=lambda p: len(places[p])) if places else None
        said = places.get(place, [])
        loops += 1
        check("%s:%d (the omp simd loop) vectorised with AVX2 (report at %s: %d vectorised, %d not)"
              % (name, loop_line, "%d:%d" % place if place else "none", said.count("optimized"),
                 said.count("missed")),
              said.count("optimized") > 0 and said.count("missed") == 0,
              "the report near the loop: %s; the reasons are in `%s`" % (places, " ".join(command)))

check("the omp simd loops were found (%d)" % loops, loops >= 8, "expected the pair loops of interaction.c, "
      "boundary.c, boulders.c and the implicit scheme's geometry.c")
sys.exit(finish())
