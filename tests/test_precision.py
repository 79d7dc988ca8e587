#!/usr/bin/python3
"""Float pair arithmetic against the all-double build on the same Poiseuille run.

Both runs write (t, y, u, u_ref) per fluid particle at t = 0.1 s and 1 s, in the same particle order.
The float build passes if its velocities differ from the double build's by much less than the
discretisation error both share, 0 < max |u_float - u_double| <= 1e-3 u_max (the two L2 errors against the
analytic solution then agree within that too, and are printed). A difference of exactly 0 fails: the two builds
would not differ in precision at all."""
import sys

import numpy as np

U_MAX = 2.5e-5


def main():
    f = np.loadtxt(sys.argv[1], delimiter=",")
    d = np.loadtxt(sys.argv[2], delimiter=",")
    if f.shape != d.shape or f.size == 0:
        print(f"FAILED: profiles differ in shape {f.shape} vs {d.shape}")
        return 1
    failed = 0
    for t in np.unique(np.round(f[:, 0], 3)):
        sel = np.round(f[:, 0], 3) == t
        diff = np.max(np.abs(f[sel, 2] - d[sel, 2])) / U_MAX
        err_f = np.sqrt(np.mean((f[sel, 2] - f[sel, 3]) ** 2)) / U_MAX
        err_d = np.sqrt(np.mean((d[sel, 2] - d[sel, 3]) ** 2)) / U_MAX
        ok = 0 < diff <= 1e-3
        failed += not ok
        print(f"t = {t:.3f} s: max |u_float - u_double| / u_max = {diff:.3g}; "
              f"L2 error float {err_f:.5f}, double {err_d:.5f}  {'ok' if ok else 'FAILED'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
