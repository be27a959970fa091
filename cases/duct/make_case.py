#!/usr/bin/env python3
"""Writes the homogeneous-turbulence duct: an OpenFOAM case (blockMeshDict and the frozen
fields U, k, epsilon, nut in 0/) for cases/duct/build.sh, which runs blockMesh on it.

    python3 cases/duct/make_case.py CASE_DIR

Geometry (m): x 0..2 (50 cells of 40 mm), y and z -0.2..0.2 in three blocks each
(-0.2..-0.04 and 0.04..0.2 in 4 cells, -0.04..0.04 in 2), 5000 cells. Patches: `inlet`
(x = 0, |y|, |z| < 0.04), `back` (the rest of x = 0), `core` (x = 2, |y|, |z| < 0.04),
`ring` (the rest of x = 2), `sides` (y, z = ±0.2); all but inlet and core are walls.
Fields: U = (1 0 0) m/s everywhere (slip on the walls, so every face value is the same),
k = 0.01 m²/s², epsilon = 0.1 m²/s³ (k/epsilon = 0.1 s), nut = 0.09 k²/epsilon.
"""
import os
import sys

X = [0.0, 2.0]
Y = [-0.2, -0.04, 0.04, 0.2]
N = [4, 2, 4]
NX = 50
U = 1.0
K = 0.01
EPS = 0.1


def header(cls, loc, obj):
    return f"""FoamFile
{{
    version     2.0;
    format      ascii;
    class       {cls};
    location    "{loc}";
    object      {obj};
}}
"""


def v(i, j, k):
    return i + 2 * (j + 4 * k)


def block_mesh():
    verts = [f"    ({X[i]:g} {Y[j]:g} {Y[k]:g})" for k in range(4) for j in range(4) for i in range(2)]
    blocks, faces = [], {"inlet": [], "back": [], "core": [], "ring": [], "sides": []}
    for k in range(3):
        for j in range(3):
            h = [v(0, j, k), v(1, j, k), v(1, j + 1, k), v(0, j + 1, k),
                 v(0, j, k + 1), v(1, j, k + 1), v(1, j + 1, k + 1), v(0, j + 1, k + 1)]
            blocks.append(f"    hex ({' '.join(map(str, h))}) ({NX} {N[j]} {N[k]}) simpleGrading (1 1 1)")
            centre = j == 1 and k == 1
            # outward normals: x = 0 is -x, x = 2 is +x
            x0 = (v(0, j, k), v(0, j, k + 1), v(0, j + 1, k + 1), v(0, j + 1, k))
            x1 = (v(1, j, k), v(1, j + 1, k), v(1, j + 1, k + 1), v(1, j, k + 1))
            faces["inlet" if centre else "back"].append(x0)
            faces["core" if centre else "ring"].append(x1)
            if j == 0:
                faces["sides"].append((v(0, 0, k), v(1, 0, k), v(1, 0, k + 1), v(0, 0, k + 1)))
            if j == 2:
                faces["sides"].append((v(0, 3, k), v(0, 3, k + 1), v(1, 3, k + 1), v(1, 3, k)))
            if k == 0:
                faces["sides"].append((v(0, j, 0), v(0, j + 1, 0), v(1, j + 1, 0), v(1, j, 0)))
            if k == 2:
                faces["sides"].append((v(0, j, 3), v(1, j, 3), v(1, j + 1, 3), v(0, j + 1, 3)))
    kinds = {"inlet": "patch", "core": "patch", "back": "wall", "ring": "wall", "sides": "wall"}
    bnd = []
    for name, fs in faces.items():
        lines = "\n".join(f"            ({' '.join(map(str, f))})" for f in fs)
        bnd.append(f"    {name}\n    {{\n        type {kinds[name]};\n        faces\n        (\n{lines}\n        );\n    }}")
    return (header("dictionary", "system", "blockMeshDict") + "\nscale 1;\n\nvertices\n(\n"
            + "\n".join(verts) + "\n);\n\nblocks\n(\n" + "\n".join(blocks)
            + "\n);\n\nedges ();\n\nboundary\n(\n" + "\n".join(bnd) + "\n);\n")


def field(cls, name, dim, value, bcs):
    body = "\n".join(f"    {p} {{ {bc} }}" for p, bc in bcs.items())
    return (header(cls, "0", name) + f"\ndimensions      {dim};\n\ninternalField   uniform {value};\n\n"
            "boundaryField\n{\n" + body + "\n}\n")


def main(argv):
    if len(argv) != 2:
        sys.exit(__doc__)
    d = argv[1]
    for sub in ("system", "constant", "0"):
        os.makedirs(os.path.join(d, sub), exist_ok=True)

    def w(rel, text):
        with open(os.path.join(d, rel), "w") as f:
            f.write(text)

    w("system/blockMeshDict", block_mesh())
    w("system/controlDict", header("dictionary", "system", "controlDict")
      + "\napplication blockMesh;\nstartFrom startTime;\nstartTime 0;\nstopAt endTime;\n"
        "endTime 0;\ndeltaT 1;\nwriteControl timeStep;\nwriteInterval 1;\nwriteFormat ascii;\n"
        "writePrecision 17;\nwriteCompression on;\ntimeFormat general;\n")
    w("system/fvSchemes", header("dictionary", "system", "fvSchemes")
      + "\nddtSchemes { default steadyState; }\ngradSchemes { default Gauss linear; }\n"
        "divSchemes { default none; }\nlaplacianSchemes { default Gauss linear corrected; }\n"
        "interpolationSchemes { default linear; }\nsnGradSchemes { default corrected; }\n")
    w("system/fvSolution", header("dictionary", "system", "fvSolution") + "\nsolvers {}\n")
    walls = ("back", "ring", "sides")
    u = f"({U:g} 0 0)"
    ubc = {"inlet": f"type fixedValue; value uniform {u};", "core": "type zeroGradient;"}
    ubc.update({p: "type slip;" for p in walls})
    w("0/U", field("volVectorField", "U", "[0 1 -1 0 0 0 0]", u, ubc))
    zg = {p: "type zeroGradient;" for p in ("inlet", "core") + walls}
    w("0/k", field("volScalarField", "k", "[0 2 -2 0 0 0 0]", f"{K:g}", zg))
    w("0/epsilon", field("volScalarField", "epsilon", "[0 2 -3 0 0 0 0]", f"{EPS:g}", zg))
    nut = 0.09 * K * K / EPS
    w("0/nut", field("volScalarField", "nut", "[0 2 -1 0 0 0 0]", f"{nut:g}",
                     {p: f"type calculated; value uniform {nut:g};" for p in ("inlet", "core") + walls}))


if __name__ == "__main__":
    main(sys.argv)
