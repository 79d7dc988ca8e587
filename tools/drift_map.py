#!/usr/bin/python3
"""drift_map: where along a belt-front run the particles drift apart from their densities.

  tools/drift_map.py RUN_DIR SNAPSHOT.vtp [SNAPSHOT.vtp ...]

For each snapshot (file names inside RUN_DIR), in 2 cm columns from the upstream wall (walls.upstream_x_m) to the
toe: the mean of (kernel-summed density) / (particle density) over fluid particles with full kernel support (more
than 2h below the column's top particle), separately in the lower 35 % ("l") and the rest ("h") of that depth.
1 means the spacing matches the densities (see tools/operator_check.py). Reads params.ini; numpy only.
"""
import argparse
import os
import sys

import numpy as np

from surgepy import cli_checks, vtp
from surgepy.run_params import ParamsError
from operator_check import kernel_sum_ratio, read_run

COLUMN_M = 0.02
LOWER_FRACTION = 0.35


def fail(message):
    cli_checks.fail("drift_map", message)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir")
    parser.add_argument("snapshots", nargs="+", metavar="SNAPSHOT.vtp", help="file names inside RUN_DIR")
    args = parser.parse_args()
    try:
        params, dp, h, mass, length = read_run(args.run_dir)
        if not params.flag("walls", "upstream"):
            fail("%s: the scene has no upstream wall (walls.upstream = false)" % params.path)
        x_wall = params.real("walls", "upstream_x_m")
    except ParamsError as e:
        fail(str(e))
    for name in args.snapshots:
        path = os.path.join(args.run_dir, name)
        try:
            s = vtp.read_vtp(path, ("time_s", "kind", "density_kgpm3"), finite=True)
        except vtp.VtpError as e:
            fail(str(e))
        x, y, rho = s["points"][:, 0], s["points"][:, 1], s["density_kgpm3"]
        fluid = np.where(s["kind"] == 0)[0]
        if fluid.size == 0:
            fail("%s: no fluid particles" % path)
        toe = x[fluid].max()
        row = []
        for x0 in np.arange(x_wall, toe, COLUMN_M):
            column = fluid[(x[fluid] >= x0) & (x[fluid] < x0 + COLUMN_M)]
            if column.size == 0:
                continue
            supported = y[column].max() - 2 * h
            cells = []
            for label, lo, hi in (("l", 0, LOWER_FRACTION), ("h", LOWER_FRACTION, 1)):
                band = column[(y[column] >= lo * supported) & (y[column] < hi * supported)]
                ratios = [kernel_sum_ratio(a, x, y, rho, mass, h, length) for a in band]
                cells.append("%s%.3f" % (label, np.mean(ratios)) if ratios else "%s  -  " % label)
            row.append("x%.2f:%s" % (x0, " ".join(cells)))
        print("t=%.1f toe %.3f:" % (s["time_s"], toe), " ".join(row))


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
