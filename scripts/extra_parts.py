#!/usr/bin/env python3
"""More machined test parts with an exact CAD truth, unlike the tuning parts (block, bracket).

    .venv-check/bin/python scripts/extra_parts.py OUT_DIR [--parts flange,wedge] [--points 200000]
                                                          [--noise 0.01] [--seed 1]

Same outputs and options as ../shared/tools/make_parts.py (NAME.step, NAME.stl, NAME.xyz,
NAME-occluded.xyz), whose helpers and writer it uses. make_parts' block and bracket are
axis-aligned; these parts are different in kind, to judge a fit on shapes it was not tuned on:
  flange       a turned part: a boss on a round disc flange, a central through bore, four bolt
               holes on a circle, a chamfered boss rim, a fillet where boss meets flange.
               Stresses: large cylinders and annular planes, circular creases, a concave fillet
               ring, a cone (the chamfer), many small holes close together.
  wedge        a block whose profile has a 30 degree inclined face, the crease between it and
               the top rounded by a fillet, and a slot milled across the top at 20 degrees to
               the part's edges. Stresses: non-orthogonal dihedral angles (150 and 120
               degrees) and creases that are not axis-aligned.
  tilted       a block with rounded vertical corners, a pocket and a through hole, rotated by
               20 deg about x, 15 deg about y, then 35 deg about z, so that no face normal and
               no edge is parallel to a coordinate axis. Stresses: voxel-grid and
               axis-aligned assumptions.
  stepped      a stepped shaft along x (three coaxial cylinders), chamfered at both ends, a
               fillet at one shoulder, a flat milled along the axis on the middle step.
               Stresses: a long, thin part, cylinders whose axis is horizontal (the occluded
               scan sees only their upper halves), a flat cutting a cylinder (straight creases
               along the axis, circular-arc creases at its end walls), concave shoulders.
  cornerblock  a block with two top corners cut off by oblique planes (triangular faces) and a
               hole drilled normal to one of them. Stresses: corners where three faces meet at
               non-right angles, a cylinder on a generic axis meeting an oblique plane.
  hexnut       a hexagonal prism with a chamfered bore. Stresses: 120-degree edges, twelve
               corners, a chamfer ring inside a hole.
  slotplate    a thin plate with a round-ended slot (walls tangent to the end cylinders: no
               crease there), a counterbored hole and a filleted corner. Stresses: tangent
               joins that must not read as creases, a step inside a hole.
  vblock       a block with a 90-degree V groove along its top, a through hole and one top edge
               filleted on one side only. Stresses: a concave crease at the groove's root, a
               fillet that ends where the top meets the end faces sharply.
  lplate       an L-shaped plate with a chamfered inner corner and a hole in each arm, rotated
               25 deg about z and 10 about x. Stresses: a concave corner, a narrow chamfer, no
               axis-aligned face.
  (vblock and lplate were added after the features' fold merge and measured unseen.)
Every part is checked to be one valid closed solid (BRepCheck_Analyzer), and every fillet and
chamfer must select at least one edge (an error otherwise).
"""
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "shared", "tools"))
import make_parts  # noqa: E402
from make_parts import box, cylinder, cut, fuse, prism, edges, edge_mid  # noqa: E402

import numpy as np  # noqa: E402

from OCP.BRepBuilderAPI import (BRepBuilderAPI_MakeFace, BRepBuilderAPI_MakePolygon,  # noqa: E402
                                BRepBuilderAPI_Transform)
from OCP.BRepCheck import BRepCheck_Analyzer  # noqa: E402
from OCP.BRepPrimAPI import BRepPrimAPI_MakeHalfSpace, BRepPrimAPI_MakePrism  # noqa: E402
from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID  # noqa: E402
from OCP.TopExp import TopExp_Explorer  # noqa: E402
from OCP.gp import gp_Ax1, gp_Dir, gp_Pln, gp_Pnt, gp_Trsf, gp_Vec  # noqa: E402

EPS = 1e-6


# ---------------------------------------------------------------- helpers

def picked(shape, pick, what):
    """Number of edges pick selects; an error if none (make_parts' fillet/chamfer would then
    silently return the shape unchanged)."""
    n = sum(1 for e in edges(shape) if pick(edge_mid(e)))
    if n == 0:
        sys.exit("%s: the pick selects no edge" % what)
    return n


def fillet(shape, radius, pick, what="fillet"):
    picked(shape, pick, what)
    return make_parts.fillet(shape, radius, pick)


def chamfer(shape, dist, pick, what="chamfer"):
    picked(shape, pick, what)
    return make_parts.chamfer(shape, dist, pick)


def prism_xz(points2d, depth):
    """A closed polygon in the y = 0 plane, given as (x, z), extruded by depth along y."""
    poly = BRepBuilderAPI_MakePolygon()
    for x, z in points2d:
        poly.Add(gp_Pnt(x, 0, z))
    poly.Close()
    face = BRepBuilderAPI_MakeFace(poly.Wire()).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0, depth, 0)).Shape()


def halfspace(point, normal):
    """The solid half-space on the side of the plane (point, normal) that normal points to."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    face = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(*point), gp_Dir(*n))).Face()
    ref = np.asarray(point, float) + 10.0 * n
    return BRepPrimAPI_MakeHalfSpace(face, gp_Pnt(*ref)).Solid()


def rotated(shape, steps):
    """shape rotated about the origin by steps [(axis, degrees), ...], applied in order."""
    total = gp_Trsf()
    for axis, deg in steps:
        t = gp_Trsf()
        t.SetRotation(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(*axis)), math.radians(deg))
        total = t.Multiplied(total)              # t after what came before
    return BRepBuilderAPI_Transform(shape, total, True).Shape()


def radius_about(m, centre, axis):
    """Distance of point m from the line through centre along unit axis."""
    d = m - np.asarray(centre, float)
    a = np.asarray(axis, float)
    return np.linalg.norm(d - d.dot(a) * a)


def count(shape, kind):
    n, e = 0, TopExp_Explorer(shape, kind)
    while e.More():
        n += 1
        e.Next()
    return n


def checked(name, build):
    """build() with a check that the result is one valid solid; prints its face count."""
    def run():
        s = build()
        solids, shells, faces = count(s, TopAbs_SOLID), count(s, TopAbs_SHELL), count(s, TopAbs_FACE)
        valid = BRepCheck_Analyzer(s).IsValid()
        print("%s: %d faces, %d solid(s), %d shell(s), %s" % (name, faces, solids, shells,
                                                            "valid" if valid else "INVALID"))
        if not valid or solids != 1 or shells != 1:
            print("WARNING: %s is not a single valid closed solid" % name, file=sys.stderr)
        return s
    return run


# ---------------------------------------------------------------- parts

def part_flange():
    """Disc flange 90 mm across, 10 thick; boss 44 across to z = 40; bore 20; 4 bolt holes of
    8 mm on a 70 mm circle; 2 mm chamfer on the boss rim; 4 mm fillet at the boss foot."""
    s = fuse(cylinder(0, 0, 0, 45.0, 10.0), cylinder(0, 0, 5, 22.0, 35.0))
    on_boss = lambda m, z: abs(m[2] - z) < EPS and abs(math.hypot(m[0], m[1]) - 22.0) < 1e-4
    s = fillet(s, 4.0, lambda m: on_boss(m, 10.0), "flange fillet")
    s = chamfer(s, 2.0, lambda m: on_boss(m, 40.0), "flange chamfer")
    s = cut(s, cylinder(0, 0, -1, 10.0, 42.0))
    for k in range(4):
        a = math.radians(45 + 90 * k)
        s = cut(s, cylinder(35 * math.cos(a), 35 * math.sin(a), -1, 4.0, 12.0))
    return s


def part_wedge():
    """80 x 50 block, 35.2 high on x < 45, then a face falling at 30 degrees to a 15 mm step at
    x = 80; 8 mm fillet on the top/incline crease; a 10 wide, 6 deep slot across the top at
    20 degrees to y."""
    h = 15.0 + 35.0 * math.tan(math.radians(30))          # 35.21
    s = prism_xz([(0, 0), (80, 0), (80, 15), (45, h), (0, h)], 50.0)
    s = fillet(s, 8.0, lambda m: abs(m[0] - 45) < EPS and abs(m[2] - h) < EPS, "wedge fillet")
    # slot: a 10 wide band whose centre line goes from (12, -5) to (12 + 60 tan 20, 55)
    t, w = math.tan(math.radians(20)), 10.0 / math.cos(math.radians(20)) / 2
    x0, x1 = 12.0 - 5 * t, 12.0 + 55 * t
    band = prism([(x0 - w, -5), (x0 + w, -5), (x1 + w, 55), (x1 - w, 55)], h + 5.0)
    s = cut(s, cut(band, box(-50, -50, -1, 150, 150, h - 6.0)))
    return s


def part_tilted():
    """A 50 x 35 x 20 block (centred on the origin) with 4 mm rounded vertical corners, a
    20 x 15 x 8 pocket and a 10 mm through hole, rotated 20 deg about x, 15 about y, 35 about z."""
    s = box(-25, -17.5, -10, 25, 17.5, 10)
    s = fillet(s, 4.0, lambda m: abs(m[2]) < EPS, "tilted fillet")
    s = cut(s, box(-19, -7.5, 2, 1, 7.5, 11))
    s = cut(s, cylinder(13, 0, -11, 5.0, 22))
    return rotated(s, [((1, 0, 0), 20.0), ((0, 1, 0), 15.0), ((0, 0, 1), 35.0)])


def part_stepped():
    """Shaft along x: radius 15 on 0..30, 11 on 30..65, 7 on 65..90. 1.5 mm chamfer at x = 0,
    1 mm at x = 90, 2 mm fillet at the x = 30 shoulder, a flat at z = 8 on x = 38..58."""
    X = (1, 0, 0)
    s = fuse(cylinder(0, 0, 0, 15.0, 30.0, X), cylinder(20, 0, 0, 11.0, 45.0, X))
    s = fuse(s, cylinder(55, 0, 0, 7.0, 35.0, X))
    ring = lambda m, x, r: abs(m[0] - x) < EPS and abs(radius_about(m, (0, 0, 0), X) - r) < 1e-4
    s = fillet(s, 2.0, lambda m: ring(m, 30.0, 11.0), "stepped fillet")
    s = chamfer(s, 1.5, lambda m: ring(m, 0.0, 15.0), "stepped chamfer 0")
    s = chamfer(s, 1.0, lambda m: ring(m, 90.0, 7.0), "stepped chamfer 90")
    s = cut(s, box(38, -20, 8, 58, 20, 20))
    return s


def part_cornerblock():
    """60 x 45 x 35 block; the (60, 45, 35) corner cut off by the plane through (35, 45, 35),
    (60, 25, 35), (60, 45, 17); the (0, 0, 35) corner by the plane through (18, 0, 35),
    (0, 14, 35), (0, 0, 23); an 8 mm hole, 12 deep, drilled normal to the first cut face."""
    s = box(0, 0, 0, 60, 45, 35)
    for a, b, c in (((35, 45, 35), (60, 25, 35), (60, 45, 17)),
                    ((18, 0, 35), (0, 14, 35), (0, 0, 23))):
        a, b, c = (np.asarray(p, float) for p in (a, b, c))
        n = np.cross(b - a, c - a)
        corner = np.array([60 if a[0] > 30 else 0, 45 if a[1] > 22 else 0, 35], float)
        if n.dot(corner - a) < 0:
            n = -n
        s = cut(s, halfspace(a, n))
    a, b, c = np.array([35., 45, 35]), np.array([60., 25, 35]), np.array([60., 45, 17])
    n = np.cross(b - a, c - a)
    n /= np.linalg.norm(n)
    n = n if n.dot(np.array([1., 1, 1])) > 0 else -n       # outward
    centre = (a + b + c) / 3
    start = centre + 1.0 * n
    s = cut(s, cylinder(*start, 4.0, 13.0, axis=tuple(-n)))
    return s


def part_hexnut():
    """Hexagonal prism 30 mm across flats, 14 tall, a 16 mm bore, a 1.2 mm chamfer on the bore's
    top rim."""
    r = 15 / math.cos(math.pi / 6)
    s = prism([(r * math.cos(math.pi / 3 * k), r * math.sin(math.pi / 3 * k)) for k in range(6)], 14)
    s = cut(s, cylinder(0, 0, -1, 8.0, 16))
    return chamfer(s, 1.2, lambda m: abs(m[2] - 14) < EPS and abs(math.hypot(m[0], m[1]) - 8) < 1e-3,
                   "hexnut chamfer")


def part_slotplate():
    """Plate 80 x 50 x 6 with a round-ended slot, a counterbored hole and one filleted corner."""
    s = box(0, 0, 0, 80, 50, 6)
    s = cut(s, box(15, 20, -1, 45, 30, 7))
    s = cut(s, cylinder(15, 25, -1, 5, 8))
    s = cut(s, cylinder(45, 25, -1, 5, 8))
    s = cut(s, cylinder(65, 25, -1, 3.5, 8))
    s = cut(s, cylinder(65, 25, 3, 6.5, 4))
    return fillet(s, 8.0, lambda m: abs(m[0] - 80) < EPS and abs(m[1] - 50) < EPS, "slotplate fillet")


def part_vblock():
    """80 x 40 x 30 block; a 90-degree V groove along x, 10 deep, its root at y = 20, z = 20;
    a 5 mm fillet on the top edge at y = 40 (before the groove is cut); an 8 mm through hole."""
    s = box(0, 0, 0, 80, 40, 30)
    s = fillet(s, 5.0, lambda m: abs(m[1] - 40) < EPS and abs(m[2] - 30) < EPS, "vblock fillet")
    root = np.array([0, 20, 20.0])
    groove = box(-1, 0, 0, 81, 40, 31)
    for n in (np.array([0, -1, 1.0]), np.array([0, 1, 1.0])):
        groove = cut(groove, halfspace(root, -n / np.linalg.norm(n)))
    s = cut(s, groove)
    return cut(s, cylinder(60, 10, -1, 4.0, 32))


def part_lplate():
    """An L-shaped plate (60 x 60, arms 20 wide, 8 thick), a 3 mm chamfer on the inner corner's
    vertical edge, a 10 mm hole in each arm; rotated 25 deg about z, then 10 about x."""
    s = prism([(0, 0), (60, 0), (60, 20), (20, 20), (20, 60), (0, 60)], 8)
    s = chamfer(s, 3.0, lambda m: abs(m[0] - 20) < EPS and abs(m[1] - 20) < EPS, "lplate chamfer")
    s = cut(s, cylinder(45, 10, -1, 5.0, 10))
    s = cut(s, cylinder(10, 45, -1, 5.0, 10))
    return rotated(s, [((0, 0, 1), 25.0), ((1, 0, 0), 10.0)])


EXTRA = {name: checked(name, f) for name, f in (
    ("flange", part_flange), ("wedge", part_wedge), ("tilted", part_tilted),
    ("stepped", part_stepped), ("cornerblock", part_cornerblock), ("hexnut", part_hexnut),
    ("slotplate", part_slotplate), ("vblock", part_vblock), ("lplate", part_lplate))}


if __name__ == "__main__":
    make_parts.main(parts=EXTRA)
