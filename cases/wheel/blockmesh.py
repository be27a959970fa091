#!/usr/bin/env python3
"""Write the blockMeshDict of a deflector-wheel classifier slice (a 2-D annulus with blades).

    python3 cases/wheel/blockmesh.py [--factor F] [--blades N] [--zone NAME] > system/blockMeshDict

Geometry (metres; the wheel turns about +z through the origin):
  the `fines` outlet: the circle r = R0 = 0.020 (the wheel's inner tube: fines leave here);
  the wheel: N = 24 radial blades from r = R1 = 0.035 to r = R2 = 0.050 (the wheel radius),
  each DELTA = 2 degrees wide (1.2 mm thick at R1, 1.7 mm at R2), equally spaced;
  the `inlet`: the circle r = R3 = 0.100 (the housing's guide vanes: air enters with swirl);
  a slice H = 0.010 thick, one cell, `frontAndBack` (type empty: a 2-D solution);
  `blades` (type wall): the blades' faces.

Mesh: 2N angular sectors alternating passage (13 degrees, 6 cells) and blade (2 degrees,
1 cell); three rings: R0-R1 8 cells, R1-R2 10 cells (passages only: the blade sectors are
left out, their faces are the blades), R2-R3 20 cells. Base counts (times --factor,
rounded, at least 1): 168 x 8 + 144 x 10 + 168 x 20 = 6 144 cells. With --zone NAME the
cells of the blade ring (R1-R2) form the cell zone NAME (an MRF rotor).
"""
import argparse
import math

R0, R1, R2, R3 = 0.020, 0.035, 0.050, 0.100
H = 0.010
DELTA = 2.0            # blade angular width, degrees
N_PASSAGE, N_BLADE = 6, 1
N_RING = (8, 10, 20)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--factor", type=float, default=1.0)
    ap.add_argument("--blades", type=int, default=24)
    ap.add_argument("--zone", default=None)
    a = ap.parse_args()
    n = a.blades
    f = a.factor
    count = lambda c: max(1, round(c * f))  # noqa: E731
    pitch = 360.0 / n
    # sector boundaries: blade k spans [k*pitch - DELTA/2, k*pitch + DELTA/2]
    angles, kinds = [], []
    for k in range(n):
        angles.append(k * pitch - DELTA / 2)
        kinds.append("blade")
        angles.append(k * pitch + DELTA / 2)
        kinds.append("passage")
    m = len(angles)  # 2n sectors, sector i from angles[i] to angles[i+1 mod m]
    radii = (R0, R1, R2, R3)

    verts = []
    index = {}

    def v(j, i, z):
        key = (j, i % m, z)
        if key not in index:
            t = math.radians(angles[i % m])
            index[key] = len(verts)
            verts.append((radii[j] * math.cos(t), radii[j] * math.sin(t), z * H))
        return index[key]

    blocks, edges, seen = [], [], set()

    def arc(j, i, z):
        a0, a1 = v(j, i, z), v(j, i + 1, z)
        if (a0, a1) in seen:
            return
        seen.add((a0, a1))
        t0 = math.radians(angles[i % m])
        t1 = math.radians(angles[(i + 1) % m] + (360.0 if i + 1 == m else 0.0))
        t = 0.5 * (t0 + t1)
        edges.append((a0, a1, (radii[j] * math.cos(t), radii[j] * math.sin(t), z * H)))

    inlet, fines, sides = [], [], []
    cells = 0
    for j in range(3):
        for i in range(m):
            if j == 1 and kinds[i] == "blade":
                continue  # the blade itself: its neighbours' faces are the `blades` wall
            nt = count(N_PASSAGE) if kinds[i] == "passage" else count(N_BLADE)
            nr = count(N_RING[j])
            b = [v(j, i, 0), v(j + 1, i, 0), v(j + 1, i + 1, 0), v(j, i + 1, 0),
                 v(j, i, 1), v(j + 1, i, 1), v(j + 1, i + 1, 1), v(j, i + 1, 1)]
            blocks.append((b, (nr, nt, 1), a.zone if j == 1 else None))
            cells += nr * nt
            for z in (0, 1):
                arc(j, i, z)
                arc(j + 1, i, z)
            if j == 2:
                inlet.append((b[1], b[2], b[6], b[5]))
            if j == 0:
                fines.append((b[0], b[4], b[7], b[3]))
            sides.append((b[0], b[3], b[2], b[1]))
            sides.append((b[4], b[5], b[6], b[7]))

    out = []
    w = out.append
    w("/*--------------------------------*- C++ -*----------------------------------*\\")
    w("  scg cases/wheel: deflector-wheel classifier slice, written by cases/wheel/blockmesh.py")
    w(f"  {n} blades, cell counts x {f}: {cells} cells")
    w("\\*---------------------------------------------------------------------------*/")
    w("FoamFile\n{\n    version     2.0;\n    format      ascii;\n    class       dictionary;\n"
      "    object      blockMeshDict;\n}\n")
    w("scale 1;\n\nvertices\n(")
    for p in verts:
        w(f"    ({p[0]:.9g} {p[1]:.9g} {p[2]:.9g})")
    w(");\n\nblocks\n(")
    for b, (nr, nt, nz), zone in blocks:
        z = f" {zone}" if zone else ""
        w(f"    hex ({' '.join(map(str, b))}){z} ({nr} {nt} {nz}) simpleGrading (1 1 1)")
    w(");\n\nedges\n(")
    for a0, a1, p in edges:
        w(f"    arc {a0} {a1} ({p[0]:.9g} {p[1]:.9g} {p[2]:.9g})")
    w(");\n\nboundary\n(")
    for name, kind, faces in (("inlet", "patch", inlet), ("fines", "patch", fines),
                              ("frontAndBack", "empty", sides)):
        w(f"    {name}\n    {{\n        type {kind};\n        faces\n        (")
        for q in faces:
            w(f"            ({' '.join(map(str, q))})")
        w("        );\n    }")
    w(");\n\ndefaultPatch\n{\n    name blades;\n    type wall;\n}\n")
    w(f"// {cells} cells")
    print("\n".join(out))


if __name__ == "__main__":
    main()
