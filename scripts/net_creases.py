#!/usr/bin/env python3
"""The crease edges of a quad net written by `scansurf fit --sharp on --net NET.obj` (or
`--features --net`) as a features file that `scansurf render --features` draws: each `l a b`
line of the net's `creases` group becomes a two-point crease (red), each node where three or
more crease edges meet a corner (blue).

    python3 scripts/net_creases.py NET.obj OUT.json
    scansurf render NET.obj -o net.png --features OUT.json

Standard library only.
"""
import json
import sys


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    net, out = sys.argv[1], sys.argv[2]
    nodes, lines = [], []
    try:
        with open(net) as f:
            for row in f:
                t = row.split()
                if t and t[0] == "v":
                    nodes.append([float(x) for x in t[1:4]])
                elif t and t[0] == "l":
                    lines.append([int(x) - 1 for x in t[1:]])
    except (OSError, ValueError) as e:
        sys.exit(f"{net}: {e}")
    if not lines:
        sys.exit(f"{net}: no crease lines (`l a b`); write the net with --sharp or --features")
    ends = {}
    for l in lines:
        for a in l:
            ends[a] = ends.get(a, 0) + 1
    doc = {
        "method": "net", "noise": 0.0, "spacing": 0.0, "diagonal": 0.0, "angle_deg": 0.0,
        "regions": 0, "region_points": [],
        "creases": [{"points": [nodes[a] for a in l], "angle_deg": 90.0, "regions": 2,
                     "closed": False} for l in lines],
        "corners": [nodes[a] for a, n in sorted(ends.items()) if n >= 3],
        "crease_length": 0.0, "seconds": 0.0,
    }
    with open(out, "w") as f:
        json.dump(doc, f)


if __name__ == "__main__":
    main()
