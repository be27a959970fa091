#!/usr/bin/env python3
"""Write the blockMeshDict of a round pipe with one 90° elbow (an O-grid, 15 blocks).

    python3 cases/elbow/blockmesh.py [--factor F] > system/blockMeshDict

Geometry (metres; y is up, gravity along -y in the scene):
  pipe diameter D = 0.05, bend radius R = 1.5 D = 0.075 (to the pipe axis);
  inlet leg along +x, axis y = 0, z = 0, from the `inlet` patch at x = -0.3 to x = 0;
  the bend turns about the axis through (0, R, 0) parallel to z, from heading +x to heading
  +y (horizontal to vertical-up, the common conveying elbow); the outer wall of the bend
  is the side away from (0, R, 0); the outlet leg along +y at x = R, from y = R to the
  `outlet` patch at y = R + 0.3. Everything else is `walls` (type wall).

Mesh: each cross-section is an O-grid: a central block of n x n cells (its corners at
0.55 D/2, its sides bulging to 0.44 D/2) and four outer blocks of n (around) x m (radial)
cells graded towards the wall (last cell / first = 0.4); along the pipe 30 cells per leg
and 24 in the bend (base counts, times --factor). Base: n = 8, m = 8 -> 320 cells per
section, 84 sections, 26 880 cells.
"""
import argparse
import math
import sys

D = 0.05
RP = D / 2           # pipe radius
RC = 1.5 * D         # bend radius (to the axis)
L_IN = 0.3           # inlet leg
L_OUT = 0.3          # outlet leg
INNER = 0.55         # O-grid square corners at INNER * RP
BULGE = 0.44         # its sides through BULGE * RP at the mid angles (straight: 0.389)
GRADING = 0.4        # radial: wall cell / inner cell


def station(kind, s):
    """Centre, outer-side unit vector e_r and tangent t of a cross-section.

    kind "in": inlet leg at x = s (s <= 0); "bend": angle s (radians, 0 .. pi/2);
    "out": outlet leg at y = RC + s (s >= 0)."""
    if kind == "in":
        return (s, 0.0, 0.0), (0.0, -1.0, 0.0)
    if kind == "bend":
        c = (RC * math.sin(s), RC - RC * math.cos(s), 0.0)
        return c, (math.sin(s), -math.cos(s), 0.0)
    return (RC, RC + s, 0.0), (1.0, 0.0, 0.0)


def point(st, r, phi):
    """The point at radius r and angle phi of a cross-section.

    phi is measured in the (e_z, e_r) plane from e_z towards e_r: e_z x e_r = t, so
    counter-clockwise in phi, advancing along t, is right-handed (blockMesh's order)."""
    c, er = st
    p, q = r * math.cos(phi), r * math.sin(phi)
    return tuple(c[i] + p * (0.0, 0.0, 1.0)[i] + q * er[i] for i in range(3))


def fmt(p):
    return "(" + " ".join(f"{x:.9g}" for x in p) + ")"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--factor", type=float, default=1.0, help="times every base cell count")
    a = ap.parse_args()
    cnt = lambda n: max(1, round(n * a.factor))
    n, m = cnt(8), cnt(8)
    n_in, n_bend, n_out = cnt(30), cnt(24), cnt(30)

    stations = [("in", -L_IN), ("bend", 0.0), ("bend", math.pi / 2), ("out", L_OUT)]
    corners = [math.pi / 4 + k * math.pi / 2 for k in range(4)]
    verts = []
    for kind, s in stations:
        st = station(kind, s)
        verts += [point(st, INNER * RP, phi) for phi in corners]   # 8 j + k: inner
        verts += [point(st, RP, phi) for phi in corners]           # 8 j + 4 + k: outer
    I = lambda j, k: 8 * j + (k % 4)
    O = lambda j, k: 8 * j + 4 + (k % 4)

    blocks, edges = [], []
    for j, cells in enumerate([n_in, n_bend, n_out]):
        blocks.append(f"    hex ({I(j,0)} {I(j,1)} {I(j,2)} {I(j,3)} {I(j+1,0)} {I(j+1,1)} {I(j+1,2)} {I(j+1,3)})"
                      f" ({n} {n} {cells}) simpleGrading (1 1 1)")
        for k in range(4):
            blocks.append(f"    hex ({I(j,k)} {O(j,k)} {O(j,k+1)} {I(j,k+1)} "
                          f"{I(j+1,k)} {O(j+1,k)} {O(j+1,k+1)} {I(j+1,k+1)})"
                          f" ({m} {n} {cells}) simpleGrading ({GRADING} 1 1)")
    # the cross-sections' arcs: the pipe wall and the O-grid square's bulging sides
    for j, (kind, s) in enumerate(stations):
        st = station(kind, s)
        for k in range(4):
            mid = corners[k] + math.pi / 4
            edges.append(f"    arc {O(j,k)} {O(j,k+1)} {fmt(point(st, RP, mid))}")
            edges.append(f"    arc {I(j,k)} {I(j,k+1)} {fmt(point(st, BULGE * RP, mid))}")
    # along the bend: arcs about the bend's axis through its 45° section
    mid_st = station("bend", math.pi / 4)
    for k in range(4):
        edges.append(f"    arc {I(1,k)} {I(2,k)} {fmt(point(mid_st, INNER * RP, corners[k]))}")
        edges.append(f"    arc {O(1,k)} {O(2,k)} {fmt(point(mid_st, RP, corners[k]))}")

    def cap(j, reverse):
        faces = [[I(j, 0), I(j, 1), I(j, 2), I(j, 3)]]
        faces += [[I(j, k), O(j, k), O(j, k + 1), I(j, k + 1)] for k in range(4)]
        return "\n".join("            (" + " ".join(map(str, f[::-1] if reverse else f)) + ")" for f in faces)

    cells = (n * n + 4 * n * m) * (n_in + n_bend + n_out)
    sys.stdout.write(f"""/*--------------------------------*- C++ -*----------------------------------*\\
  scg cases/elbow: a round pipe (D = {D} m) with one 90 degree elbow (R = {RC} m),
  horizontal (+x) to vertical-up (+y); written by cases/elbow/blockmesh.py
  (--factor {a.factor:g}): {cells} cells
\\*---------------------------------------------------------------------------*/
FoamFile
{{
    version     2.0;
    format      ascii;
    class       dictionary;
    object      blockMeshDict;
}}

scale 1;

vertices
(
{chr(10).join("    " + fmt(v) for v in verts)}
);

blocks
(
{chr(10).join(blocks)}
);

edges
(
{chr(10).join(edges)}
);

boundary
(
    inlet
    {{
        type patch;
        faces
        (
{cap(0, False)}
        );
    }}
    outlet
    {{
        type patch;
        faces
        (
{cap(3, False)}
        );
    }}
);

defaultPatch
{{
    name walls;
    type wall;
}}
""")


if __name__ == "__main__":
    main()
