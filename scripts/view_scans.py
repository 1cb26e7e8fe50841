#!/usr/bin/env python3
"""Organic models seen from one side, as partial scans never tuned on (issue 34's check).

For each model of ../shared/data (an OBJ) the surface is sampled at random (area-weighted,
`--points` points, numpy's default_rng(7)), each point with its face's normal, given Gaussian
noise of 2e-4 of the diagonal, and the points whose normal faces away from the scanner (its
component along `--axis` below zero, or above with `--from -`) are dropped: NAME-dense-occ.xyz
with `x y z nx ny nz` per line. The cut follows the surface's orientation, so the openings are
where a scanner would stop seeing: the underside, the far side of legs and ears.

usage: view_scans.py OUT_DIR [--data DIR] [--models cow,teapot] [--axis 2] [--points 100000]
"""
import argparse
import os
import sys

import numpy as np

from half_scans import points_in, read_obj  # same folder: the mesh reading and sampling


def view(v, f, n_points, axis, sign, seed=7):
    diag = np.linalg.norm(v.max(0) - v.min(0))
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    cr = np.cross(b - a, c - a)
    area = np.linalg.norm(cr, axis=1) / 2
    keep = area > 0
    a, b, c, cr, area = a[keep], b[keep], c[keep], cr[keep], area[keep]
    normal = cr / (2 * area[:, None])
    rng = np.random.default_rng(seed)
    fi = rng.choice(len(area), size=n_points, p=area / area.sum())
    p = points_in(a[fi], b[fi], c[fi], rng)
    p += rng.normal(0, 2e-4 * diag, p.shape)
    n = normal[fi]
    seen = sign * n[:, axis] >= 0
    return np.hstack([p[seen], n[seen]])


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--data", default=os.path.join(here, "../../shared/data"))
    ap.add_argument("--models", default="cow,teapot,spot,fandisk")
    ap.add_argument("--axis", type=int, default=2)
    ap.add_argument("--from", dest="side", choices=["+", "-"], default="+")
    ap.add_argument("--points", type=int, default=100000)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for m in a.models.split(","):
        path = os.path.join(a.data, m + ".obj")
        if not os.path.exists(path):
            sys.exit(f"view_scans: {path} does not exist")
        v, f = read_obj(path)
        pts = view(v, f, a.points, a.axis, 1.0 if a.side == "+" else -1.0)
        suffix = "" if (a.axis, a.side) == (2, "+") else f"-{'xyz'[a.axis]}{a.side}"
        out = os.path.join(a.out, f"{m}-dense-occ{suffix}.xyz")
        np.savetxt(out, pts, fmt="%.6f")
        print(out, len(pts))


if __name__ == "__main__":
    main()
