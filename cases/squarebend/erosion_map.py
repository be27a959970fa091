"""Draw the erosion map of `scg run --erosion-vtk FILE` as an SVG: the wall faces seen
from outside along an oblique view, the near walls left out so the inner surfaces show,
each face coloured by its depth rate (log scale), painter's order (standard library
only; legacy-VTK unstructured grid of triangles/quads/polygons as scg writes it).

    python3 cases/squarebend/erosion_map.py EROSION.vtk OUT.svg [--view X Y Z]
"""
import math
import sys


def read(path):
    tok = open(path).read().split()
    i = tok.index("POINTS")
    n = int(tok[i + 1])
    pts = [tuple(float(tok[i + 3 + 3 * k + j]) for j in range(3)) for k in range(n)]
    i = tok.index("CELLS")
    nc = int(tok[i + 1])
    j = i + 3
    cells = []
    for _ in range(nc):
        m = int(tok[j])
        cells.append([int(x) for x in tok[j + 1:j + 1 + m]])
        j += m + 1
    i = tok.index("depth_rate_m_per_s")
    rate = [float(x) for x in tok[i + 5:i + 5 + nc]]
    return pts, cells, rate


def colour(t):
    """t in 0..1 → a dark-blue to yellow ramp."""
    stops = [(0.0, (40, 30, 90)), (0.35, (40, 110, 160)), (0.7, (90, 190, 110)), (1.0, (250, 230, 60))]
    for (a, ca), (b, cb) in zip(stops, stops[1:]):
        if t <= b:
            u = (t - a) / (b - a)
            return tuple(round(x + (y - x) * u) for x, y in zip(ca, cb))
    return stops[-1][1]


def main(argv):
    src, out = argv[1], argv[2]
    view = (-0.55, -0.25, 0.8)
    if "--view" in argv:
        k = argv.index("--view")
        view = tuple(float(x) for x in argv[k + 1:k + 4])
    n = math.sqrt(sum(v * v for v in view))
    d = tuple(v / n for v in view)  # toward the viewer
    up0 = (0.0, 0.0, 1.0) if abs(d[2]) < 0.9 else (0.0, 1.0, 0.0)
    ex = (up0[1] * d[2] - up0[2] * d[1], up0[2] * d[0] - up0[0] * d[2], up0[0] * d[1] - up0[1] * d[0])
    ne = math.sqrt(sum(v * v for v in ex))
    ex = tuple(v / ne for v in ex)
    ey = (d[1] * ex[2] - d[2] * ex[1], d[2] * ex[0] - d[0] * ex[2], d[0] * ex[1] - d[1] * ex[0])
    pts, cells, rate = read(src)
    pos = [r for r in rate if r > 0]
    # three decades below the deepest (grazing impacts wear orders of magnitude less)
    hi = math.log10(max(pos)) if pos else 1.0
    lo = max(math.log10(min(pos)), hi - 3.0) if pos else 0.0
    faces = []
    for c, r in zip(cells, rate):
        p = [pts[i] for i in c]
        a, b, q = p[0], p[1], p[2]
        u = [b[k] - a[k] for k in range(3)]
        v = [q[k] - a[k] for k in range(3)]
        nrm = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        # the wall's outward normal toward the viewer: a near wall, left out
        if sum(nrm[k] * d[k] for k in range(3)) > 0:
            continue
        depth = sum(sum(x[k] for x in p) / len(p) * d[k] for k in range(3))
        xy = [(sum(x[k] * ex[k] for k in range(3)), -sum(x[k] * ey[k] for k in range(3))) for x in p]
        faces.append((depth, xy, r))
    faces.sort(key=lambda f: f[0])
    xs = [x for f in faces for x, _ in f[1]]
    ys = [y for f in faces for _, y in f[1]]
    w, h = 900, 700
    s = min((w - 40) / (max(xs) - min(xs)), (h - 110) / (max(ys) - min(ys)))
    ox, oy = 20 - min(xs) * s, 20 - min(ys) * s
    body = []
    for _, xy, r in faces:
        t = 0.0 if r <= 0 else max(0.0, (math.log10(r) - lo) / max(hi - lo, 1e-12))
        col = "rgb(225,225,225)" if r <= 0 else "rgb(%d,%d,%d)" % colour(t)
        ptxt = " ".join(f"{x * s + ox:.1f},{y * s + oy:.1f}" for x, y in xy)
        body.append(f'<polygon points="{ptxt}" fill="{col}" stroke="{col}" stroke-width="0.3"/>')
    leg = []
    for k in range(11):
        t = k / 10
        leg.append(f'<rect x="{60 + k * 40}" y="{h - 60}" width="40" height="16" fill="rgb(%d,%d,%d)"/>' % colour(t))
    title = open(src).read().split("\n")[1]
    leg.append(f'<text x="{w - 20}" y="30" font-size="16" font-family="sans-serif" text-anchor="end">{title}</text>')
    leg.append(f'<text x="60" y="{h - 70}" font-size="14" font-family="sans-serif">wear depth rate, m/s '
               f'(log scale, three decades; grey: no impact)</text>')
    leg.append(f'<text x="60" y="{h - 28}" font-size="13" font-family="sans-serif">{10 ** lo:.1e}</text>')
    leg.append(f'<text x="470" y="{h - 28}" font-size="13" font-family="sans-serif" text-anchor="end">{10 ** hi:.1e}</text>')
    svg = (f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}">'
           f'<rect width="{w}" height="{h}" fill="white"/>' + "".join(body) + "".join(leg) + "</svg>")
    with open(out, "w") as f:
        f.write(svg)
    print(f"wrote {out}: {len(faces)} faces drawn")


if __name__ == "__main__":
    sys.exit(main(sys.argv))
