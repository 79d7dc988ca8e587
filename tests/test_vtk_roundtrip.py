#!/usr/bin/python3
"""Decodes DIR/synthetic.vtp written by tests/test_vtk_output.c with python/surgepy/vtp.py and checks that
every value equals the known one exactly.

Usage: test_vtk_roundtrip.py DIR/synthetic.vtp
If DIR/synthetic.pvd exists (the C test writes it), read_pvd is checked on it as well.

Known values (keep in sync with tests/test_vtk_output.c):
  step = 1234567890123, time_s = 12.345678901234567, 5 particles:
  i  x_m           y_m      vx_mps  vy_mps   density  pressure  kind  id
  0  -1.25         0.5      -3.5    2.25     998.5    -1250.75  0     7
  1  0.1           -2.75    2.25    -0.5     1000.25  0.0       1     0
  2  1e-300        2.5e-8   0.1     -0.1     1002.0   3.0e5     2     -1
  3  -123456.789   7.0e10   -1e-3   65504.0  999.875  -0.1      1     2147483647
  4  3.0           -1e-5    1e30    -7.0     1001.125 123.456   0     42
  The Float32 columns are the float32 roundings of these doubles.
"""

import os
import sys

import numpy as np

from surgepy import vtp  # noqa: E402

X = [-1.25, 0.1, 1e-300, -123456.789, 3.0]
Y = [0.5, -2.75, 2.5e-8, 7.0e10, -1e-5]
VX = [-3.5, 2.25, 0.1, -1e-3, 1e30]
VY = [2.25, -0.5, -0.1, 65504.0, -7.0]
RHO = [998.5, 1000.25, 1002.0, 999.875, 1001.125]
P = [-1250.75, 0.0, 3.0e5, -0.1, 123.456]
KIND = [0, 1, 2, 1, 0]
ID = [7, 0, -1, 2147483647, 42]
STEP = 1234567890123
TIME_S = 12.345678901234567
N = len(X)

EXPECTED_PVD = [
    (0.0, "synthetic_0.vtp"),
    (0.1, 'sub dir/a&b<c>".vtp'),
    (0.2, "synthetic.vtp"),
]

failures = []


def check_array(name, got, expected, dtype, shape):
    expected = np.array(expected, dtype=dtype)
    if got is None:
        failures.append("%s: missing" % name)
    elif got.dtype != np.dtype(dtype):
        failures.append("%s: dtype %s, expected %s" % (name, got.dtype, np.dtype(dtype)))
    elif got.shape != shape:
        failures.append("%s: shape %s, expected %s" % (name, got.shape, shape))
    elif not np.array_equal(got, expected):
        failures.append("%s: got %r, expected %r" % (name, got.tolist(), expected.tolist()))


def main():
    if len(sys.argv) != 2:
        print("usage: %s DIR/synthetic.vtp" % sys.argv[0], file=sys.stderr)
        return 2
    path = sys.argv[1]
    d = vtp.read_vtp(path)

    zeros = [0.0] * N
    check_array("points", d.get("points"), np.column_stack([X, Y, zeros]), np.float64, (N, 3))
    check_array("velocity_mps", d.get("velocity_mps"),
                np.column_stack([np.float32(VX), np.float32(VY), zeros]), np.float32, (N, 3))
    check_array("density_kgpm3", d.get("density_kgpm3"), RHO, np.float32, (N,))
    check_array("pressure_pa", d.get("pressure_pa"), P, np.float32, (N,))
    check_array("kind", d.get("kind"), KIND, np.uint8, (N,))
    check_array("id", d.get("id"), ID, np.int32, (N,))
    check_array("verts_connectivity", d.get("verts_connectivity"), range(N), np.int64, (N,))
    check_array("verts_offsets", d.get("verts_offsets"), range(1, N + 1), np.int64, (N,))
    if d.get("time_s") != TIME_S or not isinstance(d.get("time_s"), float):
        failures.append("time_s: got %r, expected %r" % (d.get("time_s"), TIME_S))
    if d.get("step") != STEP or not isinstance(d.get("step"), int):
        failures.append("step: got %r, expected %r" % (d.get("step"), STEP))
    expected_keys = {"points", "verts_connectivity", "verts_offsets", "velocity_mps", "density_kgpm3",
                     "pressure_pa", "kind", "id", "time_s", "step"}
    if set(d) != expected_keys:
        failures.append("keys: got %s, expected %s" % (sorted(d), sorted(expected_keys)))

    pvd_path = os.path.join(os.path.dirname(path), "synthetic.pvd")
    try:
        entries = vtp.read_pvd(pvd_path)
        if entries != EXPECTED_PVD:
            failures.append("read_pvd: got %r, expected %r" % (entries, EXPECTED_PVD))
    except vtp.VtpError as e:  # missing or malformed: the C test writes it
        failures.append("read_pvd: %s" % e)

    empty_path = os.path.join(os.path.dirname(path), "empty.vtp")  # a snapshot with no particles
    try:
        e = vtp.read_vtp(empty_path)
        if e["points"].shape[0] != 0 or set(e) != expected_keys or any(len(e[k]) for k in expected_keys
                                                                         if k not in ("time_s", "step")):
            failures.append("empty.vtp: got %s" % {k: getattr(v, "shape", v) for k, v in e.items()})
    except vtp.VtpError as err:
        failures.append("empty.vtp: %s" % err)

    for failure in failures:
        print("FAIL " + failure, file=sys.stderr)
    if failures:
        return 1
    print("test_vtk_roundtrip: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
