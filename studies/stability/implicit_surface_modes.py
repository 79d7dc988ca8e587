#!/usr/bin/python3
"""The implicit step's growth factor on a frozen lattice under a free surface (docs/validation/stability.md,
"Short steps in a thin fluid").

With the particles held still, one step of the implicit scheme (sim/src/scheme/implicit/) is a linear map of the
velocities and the pressure. This script builds that map as matrices, the same pair terms as the C code, on a
lattice slab periodic in x with a free surface at its top and bottom (one row of surface particles each, held at
p = 0), and prints its spectral radius, the factor by which its fastest mode grows a step:

    p_r = p_n - beta (L p_n) / diag(L)                  (the relaxation, implicit.pressure_relaxation)
    v* = (I + nu dt Lv)^-1 (v_n - dt G p_r / rho0)      (the predictor; Lv the viscous Laplacian)
    L phi = -(rho0 / dt) D v*                           (L the corrected Laplacian, D the renormalised divergence)
    v_n+1 = v* - dt G phi / rho0,  p_n+1 = p_r + phi    (G the renormalised gradient)

With q = dt p / rho0 only kappa = nu dt / dp^2 is left. A radius above 1 means the step is unstable on a frozen
lattice; the moving particles of a real run then decide whether it shows. The rows:
`cut-off kernels` are the operators with implicit.surface_images = 0 (the kernels under the surface cut off);
`g_vacuum` drops the gradient's own term (p_b instead of p_b - p_a: air at p = 0 beyond the surface), `d_adjoint`
takes -G^T as the divergence, `g_adjoint` -D^T as the gradient; `air` holds no surface particle at p = 0 but
mirrors every particle across a surface half a spacing beyond the outer rows; `images` is the scheme's default
(implicit.surface_images = 1): the surface rows hold p = 0 and every other particle within reach sees the mirror
images of its neighbours across the surface rows' line (pressure negated, velocity kept), without relaxation and
with the default relaxation beta = 0.5.

    /usr/bin/python3 studies/stability/implicit_surface_modes.py [--columns 8] [--rows 16] [--ch 1.8]
"""
import argparse
import sys

import numpy as np

from surgepy import cli_checks

KAPPAS = (0.0, 0.01, 0.05, 0.2, 1.0)


def wendland_factor(r, h):
    """F with grad_a W_ab = F r_ab (sim/src/physics/kernel.h)"""
    alpha = 7.0 / (4.0 * np.pi * h * h)
    q = r / h
    return np.where(q < 2, -5.0 * alpha / h ** 2 * (1 - q / 2) ** 3, 0.0)


def operators(columns, rows, ch, mirror=None, dp=0.01, rho0=1000.0):
    """G (2n x n), D (n x 2n), L and Lv (n x n) on the slab, and which particles are surface particles (held at
    p = 0). mirror "air": no particle is held, each one within 2h of a surface has a mirror image across it (the
    surfaces half a spacing beyond the outer rows); mirror "images": the outer rows are held at p = 0 and the others
    have images across the outer rows' lines. An image's pressure is its particle's negated (p = 0 on the surface),
    its velocity its particle's own, so that every kernel is full."""
    h = ch * np.sqrt(2.0) * dp
    xs, ys = np.meshgrid((np.arange(columns) + 0.5) * dp, (np.arange(rows) + 0.5) * dp)
    pos = np.c_[xs.ravel(), ys.ravel()]
    n = len(pos)
    row = np.round(pos[:, 1] / dp - 0.5).astype(int)
    edge = (row == 0) | (row == rows - 1)
    surface = np.zeros(n, bool) if mirror == "air" else edge
    # the neighbours (the particles and their images) and their values as rows of the particles'
    images = []
    if mirror:
        top, bottom = (rows, 0.0) if mirror == "air" else (rows - 0.5, 0.5)
        top *= dp
        bottom *= dp
        for i, (x, y) in enumerate(pos):
            if mirror == "images" and edge[i]:
                continue
            if top - y < 2 * h:
                images.append((i, (x, 2 * top - y)))
            if y - bottom < 2 * h:
                images.append((i, (x, 2 * bottom - y)))
    source = np.array([i for i, _ in images], int)
    others = np.vstack([pos] + ([np.array([q for _, q in images])] if images else []))
    pressure_of = np.vstack([np.eye(n), -np.eye(n)[source]])
    velocity_of = np.vstack([np.eye(n), np.eye(n)[source]])
    d = pos[:, None, :] - others[None, :, :]  # r_ab
    d[..., 0] -= columns * dp * np.round(d[..., 0] / (columns * dp))
    r2 = (d ** 2).sum(-1)
    f = wendland_factor(np.sqrt(r2), h)
    f[np.arange(n), np.arange(n)] = 0.0
    vol = dp * dp
    g = vol * f[..., None] * d  # V_b grad_a W_ab
    eta2 = 0.01 * h * h
    w = -4 * rho0 * vol * f * r2 / (2 * rho0 * (r2 + eta2))  # the Laplacian's pair weight (eq. 7 per unit viscosity)
    moment = -np.einsum('ab,abi,abj->aij', vol * f, d, d)
    minv = np.linalg.inv(moment)
    G = np.zeros((2 * n, n))
    D = np.zeros((n, 2 * n))
    L = np.zeros((n, n))
    Lv = np.zeros((n, n))
    for a in range(n):
        mg = g[a] @ minv[a]  # row b: M_a^-1 V_b grad_a W_ab (M symmetric)
        G[a] += mg[:, 0] @ pressure_of
        G[n + a] += mg[:, 1] @ pressure_of
        G[a, a] -= mg[:, 0].sum()  # grad p_a = M^-1 sum_b V_b (p_b - p_a) grad_a W_ab
        G[n + a, a] -= mg[:, 1].sum()
        D[a, :n] += mg[:, 0] @ velocity_of  # div v_a = tr(M^-1 sum_b V_b (v_b - v_a) x grad_a W_ab)
        D[a, a] -= mg[:, 0].sum()
        D[a, n:] += mg[:, 1] @ velocity_of
        D[a, n + a] -= mg[:, 1].sum()
        u = minv[a] @ (w[a][:, None] * d[a]).sum(0)
        c = w[a] + g[a] @ u  # -lap p_a = sum_b (w_ab + u_a . V_b grad_a W_ab)(p_a - p_b)
        L[a] -= c @ pressure_of
        L[a, a] += c.sum()
        Lv[a] -= w[a] @ velocity_of
        Lv[a, a] += w[a].sum()
    return dict(G=G, D=D, L=L, Lv=Lv * dp * dp, surface=surface, n=n, beta=0.0)


def step_matrix(ops, kappa):
    """The step's linear map on (v, q) with q = dt p / rho0 on the particles under the surface"""
    n, free = ops["n"], ~ops["surface"]
    Gq = ops["G"][:, free]
    L = ops["L"][np.ix_(free, free)]
    relaxed = np.eye(free.sum()) - ops["beta"] * L / np.diag(L)[:, None]
    viscous = np.linalg.inv(np.eye(2 * n) + kappa * np.kron(np.eye(2), ops["Lv"]))
    v_star = np.hstack([viscous, -viscous @ Gq @ relaxed])
    phi = -np.linalg.solve(L, ops["D"][free] @ v_star)
    v_next = v_star - Gq @ phi
    q_next = np.hstack([np.zeros((free.sum(), 2 * n)), relaxed]) + phi
    return np.vstack([v_next, q_next])


def variants(ops, air_ops, image_ops):
    n = ops["n"]
    G_vacuum = ops["G"].copy()
    G_vacuum[np.arange(n), np.arange(n)] = 0.0  # its own term, p_a, out of each component
    G_vacuum[n + np.arange(n), np.arange(n)] = 0.0
    return [("cut-off kernels (surface_images 0)", ops),
            ("g_vacuum: gradient without its own term", dict(ops, G=G_vacuum)),
            ("d_adjoint: divergence -G^T", dict(ops, D=-ops["G"].T)),
            ("g_adjoint: gradient -D^T", dict(ops, G=-ops["D"].T)),
            ("air: mirror images beyond the surface", air_ops),
            ("images, no relaxation", image_ops),
            ("images, relaxation 0.5 (the default)", dict(image_ops, beta=0.5))]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--columns", type=cli_checks.positive_int, default=8,
                        help="lattice columns (periodic; default 8)")
    parser.add_argument("--rows", type=cli_checks.positive_int, default=16,
                        help="lattice rows, the surface rows included (default 16)")
    parser.add_argument("--ch", type=cli_checks.positive, default=1.8, help="C_h, h = C_h sqrt(2) dp (default 1.8)")
    args = parser.parse_args(argv)
    if args.columns < 6 or args.rows < 8 or not 1.0 <= args.ch <= 2.5:
        cli_checks.fail("implicit_surface_modes", "--columns >= 6, --rows >= 8 and 1 <= --ch <= 2.5 (the kernel must "
                        "fit the period), got %d, %d, %g" % (args.columns, args.rows, args.ch))
    ops = operators(args.columns, args.rows, args.ch)
    image_ops = operators(args.columns, args.rows, args.ch, mirror="images")
    for name, o in (("cut-off kernels", ops), ("images", image_ops)):
        free = ~o["surface"]
        mu = np.linalg.eigvals(np.linalg.solve(o["L"][np.ix_(free, free)], -o["D"][free] @ o["G"][:, free]))
        print("C_h %g, %d x %d lattice, %s: eigenvalues of L^-1 (-D G) from %.5f to %.4f (%d below -1e-9; the "
              "incremental step is stable on a frozen lattice where all lie in [0, 4/3))"
              % (args.ch, args.columns, args.rows, name, mu.real.min(), mu.real.max(), (mu.real < -1e-9).sum()))
    print("spectral radius of one step at nu dt / dp^2 = " + ", ".join("%g" % k for k in KAPPAS))
    for name, variant in variants(ops, operators(args.columns, args.rows, args.ch, mirror="air"), image_ops):
        radii = [np.abs(np.linalg.eigvals(step_matrix(variant, k))).max() for k in KAPPAS]
        print("  %-42s %s" % (name, "  ".join("%.4f" % r for r in radii)))
    return 0


if __name__ == "__main__":
    sys.exit(cli_checks.run(main))
