#!/usr/bin/env python3
"""How often OpenCASCADE's default point projection misses the edge points of a STEP model.

    .venv-check/bin/python scripts/occ_projection_misses.py MODEL.step [--list N]

Reads the file with cad_check's reader (../shared/tools/cad_check.py), sews it the same way,
and at 5 points of every edge shared by two faces (cad_check's normal-jump samples) projects
the point onto both faces' surfaces twice: with GeomAPI_ProjectPointOnSurf's default
(Extrema_ExtAlgo_Grad, what cad_check uses) and with Extrema_ExtAlgo_Tree. A projection whose
distance exceeds 1e-7 is a miss (the point lies on the face). Prints one JSON line: the number
of projections, the misses of each algorithm, the samples whose normal jump exceeds 5 degrees
with each, and how many of the default's are at a miss; with --list, the first N misses.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "shared", "tools"))
import cad_check  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("model")
    ap.add_argument("--list", type=int, default=0, help="print the first N misses")
    a = ap.parse_args()
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Sewing
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.Extrema import Extrema_ExtAlgo_Tree
    from OCP.GeomAPI import GeomAPI_ProjectPointOnSurf
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_REVERSED
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    shape, _ = cad_check.read_shape(a.model)
    if shape is None:
        sys.exit(f"{a.model}: not readable")
    faces = cad_check.faces_of(shape)
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(shape, box, False, False)
    diag = box.CornerMin().Distance(box.CornerMax())
    sew = BRepBuilderAPI_Sewing(1e-4 * diag)
    sew.Add(shape)
    sew.Perform()
    sewn = sew.SewedShape()
    owners = {}
    for f in cad_check.faces_of(sewn):
        e = TopExp_Explorer(f, TopAbs_EDGE)
        while e.More():
            owners.setdefault(hash(e.Current()), [e.Current(), []])[1].append(f)
            e.Next()
    res = {"model": os.path.basename(a.model), "faces": len(faces), "projections": 0,
           "misses_default": 0, "misses_tree": 0, "over_5_deg_default": 0,
           "over_5_deg_tree": 0, "over_5_deg_default_at_a_miss": 0}
    listed = []
    for edge_shape, fl in owners.values():
        if len(fl) != 2:
            continue
        c = BRepAdaptor_Curve(TopoDS.Edge(edge_shape))
        t0, t1 = c.FirstParameter(), c.LastParameter()
        for k in range(5):
            p = c.Value(t0 + (t1 - t0) * (k + 0.5) / 5)
            normals = {"default": [], "tree": []}
            missed = False
            for f in fl:
                s = BRep_Tool.Surface_s(f)
                sgn = -1.0 if f.Orientation() == TopAbs_REVERSED else 1.0
                for name, proj in (("default", GeomAPI_ProjectPointOnSurf(p, s)),
                                   ("tree", GeomAPI_ProjectPointOnSurf(p, s, Extrema_ExtAlgo_Tree))):
                    u, v = proj.LowerDistanceParameters()
                    if proj.LowerDistance() > 1e-7:
                        res["misses_" + name] += 1
                        if name == "default":
                            missed = True
                            if len(listed) < a.list:
                                listed.append({"point": [p.X(), p.Y(), p.Z()], "u": u, "v": v,
                                               "distance": proj.LowerDistance()})
                    n = BRepLProp_SLProps(BRepAdaptor_Surface(f), u, v, 1, 1e-9).Normal()
                    normals[name].append(np.array([n.X(), n.Y(), n.Z()]) * sgn)
                res["projections"] += 1
            for name, ns in normals.items():
                ang = math.degrees(math.acos(min(1.0, abs(float(np.dot(ns[0], ns[1]))))))
                if ang > 5.0:
                    res["over_5_deg_" + name] += 1
                    if name == "default" and missed:
                        res["over_5_deg_default_at_a_miss"] += 1
    if a.list:
        res["first_misses"] = listed
    print(json.dumps(res))


if __name__ == "__main__":
    main()
