#!/usr/bin/env python3
"""Peer timing for `fill-holes`: pymeshlab's meshing_close_holes on the same meshes, single-threaded.

usage: OMP_NUM_THREADS=1 .venv-bench/bin/python scripts/peer_close_holes.py MESH [MESH ...]

For each mesh: boundary loops before, time of meshing_close_holes (maxholesize large enough for
every hole, self-intersection check on, the default), loops left after, triangles added. The
2M-triangle sphere with 50 holes is written by `FILL_HOLES_BENCH_MESH=path cargo bench --bench
fill_holes`. The venv comes from ../shared/tools/requirements-bench.txt (not committed).
"""
import os, sys, time
import numpy as np
import pymeshlab as ml
import trimesh


def loops(v, f):
    m = trimesh.Trimesh(v, f, process=False)
    edges = m.edges_sorted
    uniq, counts = np.unique(edges, axis=0, return_counts=True)
    boundary = uniq[counts == 1]
    # Count loops by union-find over boundary edges.
    parent = {}
    def find(x):
        while parent.setdefault(x, x) != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x
    for a, b in boundary:
        parent[find(a)] = find(b)
    return len({find(a) for a, _ in boundary}), len(boundary)


for path in sys.argv[1:]:
    for refine in (False, True):
        ms = ml.MeshSet()
        ms.load_new_mesh(path)
        m = ms.current_mesh()
        v, f = m.vertex_matrix(), m.face_matrix()
        nloops, nedges = loops(v, f)
        # Refinement to the mean edge length, as our fills do.
        tm = trimesh.Trimesh(v, f, process=False)
        el = tm.edges_unique_length.mean()
        extra = {}
        if refine:
            extra = dict(refinehole=True,
                         refineholeedgelen=ml.PercentageValue(100.0 * el / tm.bounding_box.extents.max() / 3 ** 0.5))
        t = time.time()
        ms.meshing_close_holes(maxholesize=max(30, nedges + 1), **extra)
        dt = time.time() - t
        out = ms.current_mesh()
        after, _ = loops(out.vertex_matrix(), out.face_matrix())
        print("%s: %d faces, %d holes (%d boundary edges); meshing_close_holes%s %.3f s, "
              "%d holes left, %d triangles added (OMP_NUM_THREADS=%s)"
              % (os.path.basename(path), len(f), nloops, nedges, " refinehole" if refine else "",
                 dt, after, out.face_number() - len(f), os.environ.get("OMP_NUM_THREADS", "unset")))
