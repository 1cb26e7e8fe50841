#!/usr/bin/env python3
"""Front halves of organic models as partial scans never tuned on (issue 34's check).

For each model of ../shared/data (an OBJ) and each axis, the surface is sampled at random
(area-weighted, one point per `spacing`^2 of area on average, numpy's default_rng(11)), given
Gaussian noise of 1e-4 of the diagonal, and the points above the vertices' mean along the axis
are kept: NAME-hAXIS.xyz. The cut runs through the model (a cow cut at z: through the body, an
ear and the tail), so the openings are the cut's rim, not what a scanner's view would leave.

usage: half_scans.py OUT_DIR [--data DIR] [--models cow,spot] [--axes 0,1,2] [--spacing 0.003]
"""
import argparse
import os
import sys

import numpy as np


def read_obj(path):
    v, f = [], []
    with open(path) as fh:
        for line in fh:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                v.append([float(x) for x in t[1:4]])
            elif t[0] == "f":
                idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
                f.extend([idx[0], idx[k], idx[k + 1]] for k in range(1, len(idx) - 1))
    return np.array(v), np.array(f)


def points_in(a, b, c, rng):
    """One uniform random point in each triangle (a[i], b[i], c[i]) (folded barycentrics)."""
    u, w = rng.random(len(a)), rng.random(len(a))
    flip = u + w > 1
    u[flip], w[flip] = 1 - u[flip], 1 - w[flip]
    return a + u[:, None] * (b - a) + w[:, None] * (c - a)


def half(v, f, axis, spacing_rel, seed=11):
    diag = np.linalg.norm(v.max(0) - v.min(0))
    s = spacing_rel * diag
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    area = np.linalg.norm(np.cross(b - a, c - a), axis=1) / 2
    rng = np.random.default_rng(seed)
    fi = np.repeat(np.arange(len(f)), rng.poisson(area / (s * s)))
    p = points_in(a[fi], b[fi], c[fi], rng)
    p += rng.normal(0, 1e-4 * diag, p.shape)
    return p[p[:, axis] > v[:, axis].mean()]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out")
    ap.add_argument("--data", default=os.path.join(here, "../../shared/data"))
    ap.add_argument("--models", default="cow,spot,fandisk,beetle,alligator")
    ap.add_argument("--axes", default="0,1,2")
    ap.add_argument("--spacing", type=float, default=0.003)
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    for m in a.models.split(","):
        path = os.path.join(a.data, m + ".obj")
        if not os.path.exists(path):
            sys.exit(f"half_scans: {path} does not exist")
        v, f = read_obj(path)
        for axis in (int(x) for x in a.axes.split(",")):
            p = half(v, f, axis, a.spacing)
            out = os.path.join(a.out, f"{m}-h{axis}.xyz")
            np.savetxt(out, p, fmt="%.6f")
            print(out, len(p))


if __name__ == "__main__":
    main()
