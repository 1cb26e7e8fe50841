#!/usr/bin/env python3
"""Where a fit misses the true sharp edges of a part: the worst spots of part_check's crease.

part_check.py gives the largest distance of the true sharp edges from the fit (`crease
distance_max`); this lists where it comes from, so that a spot can be followed back to the cells
and mesh edges beside it. The true edges (faces meeting at more than 30 degrees, points every
0.2 % of the diagonal, as part_check samples them) are measured against the fit, and the spots
over `--bar` (relative to the diagonal) are printed worst first, one per `--radius` mm, each with
how many edge samples near it are over the bar.

With --flipped it lists instead where part_check's `flipped_area` comes from: the true surface's
samples (part_check's, same seed) at which the fit's normal is more than 90 degrees off, with
their distance to the nearest true sharp edge.

usage: crease_spots.py FIT.(ply|stl|obj|step) TRUTH.step [--bar 5e-4] [--radius 2] [--top 25]
                       [--flipped]
Needs the checker's venv (numpy, scipy, OCP, trimesh) and ../shared/tools beside the repository.
"""
import argparse
import os
import sys

import numpy as np

TOOLS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "tools")
sys.path.insert(0, TOOLS)
import part_check as pc  # noqa: E402
from cad_check import read_shape  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("fit")
    ap.add_argument("truth")
    ap.add_argument("--bar", type=float, default=5e-4)
    ap.add_argument("--radius", type=float, default=2.0)
    ap.add_argument("--top", type=int, default=25)
    ap.add_argument("--flipped", action="store_true")
    a = ap.parse_args()
    shape = read_shape(a.truth)[0]
    V0, T0 = pc.tessellate(shape, 0.01)[:2]
    diag = float(np.linalg.norm(V0.max(0) - V0.min(0)))
    if a.fit.lower().endswith((".step", ".stp")):
        V, T, N = pc.tessellate(read_shape(a.fit)[0], 5e-5 * diag)
    else:
        V, T, N = pc.mesh_fit(a.fit)[:3]
    crease = pc.sharp_edge_points(shape, 30, 0.002 * diag)
    if a.flipped:
        flipped(shape, V, T, N, crease, a)
        return
    if len(crease) == 0:
        print("no sharp edges in the truth")
        return
    d = pc.closest(crease, V, T, 0.003 * diag)[0]
    bar = a.bar * diag
    print(f"{len(crease)} edge samples, max {d.max() / diag:.2e}, p95 "
          f"{np.quantile(d, 0.95) / diag:.2e}, over {a.bar:g}: {np.mean(d > bar) * 100:.2f} %")
    spots = []
    for i in np.argsort(-d):
        if d[i] <= bar or len(spots) >= a.top:
            break
        if any(np.linalg.norm(crease[i] - s) < a.radius for s in spots):
            continue
        spots.append(crease[i])
        near = np.linalg.norm(crease - crease[i], axis=1) < a.radius
        print(f"  {np.round(crease[i], 2)}  {d[i] / diag:.2e}  ({int(np.sum(near & (d > bar)))} near over)")


def flipped(shape, V, T, N, crease, a):
    """The samples behind part_check's flipped_area (part_check's sampling, same seed)."""
    from scipy.spatial import cKDTree
    rng = np.random.default_rng(7)
    Vt, Tt, Nt = pc.tessellate(shape, 0.002)
    diag = float(np.linalg.norm(Vt.max(0) - Vt.min(0)))
    pt, nt, _ = pc.sample(Vt, Tt, 100000, rng, Nt)
    _, tri, q = pc.closest(pt, V, T, 0.003 * diag)
    ang = np.degrees(np.arccos(np.clip((pc.normal_at(V, T, N, tri, q) * nt).sum(1), -1, 1)))
    dc = cKDTree(crease).query(pt)[0] if len(crease) else np.full(len(pt), np.inf)
    bad = np.flatnonzero(ang > 90)
    print(f"{len(bad)} of {len(pt)} samples flipped (flipped_area {len(bad) / len(pt):.0e})")
    for i in bad[np.argsort(dc[bad])][: a.top]:
        print(f"  {np.round(pt[i], 3)}  {ang[i]:.0f} deg, {dc[i]:.3f} from a sharp edge, "
              f"fit point {np.round(q[i], 3)}")


if __name__ == "__main__":
    main()
