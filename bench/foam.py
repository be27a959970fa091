"""Helpers of bench/vs-openfoam.sh (standard library only).

  python3 bench/foam.py case DIR N STEPS SEED INTERP   the OpenFOAM case DIR (templates of
                                                       bench/openfoam/ filled in, the N
                                                       parcel positions) and DIR/scene.toml,
                                                       scg's scene of the same run; STEPS
                                                       steps, written at the last one;
                                                       INTERP is scg's name of OpenFOAM's
                                                       cellPoint
  python3 bench/foam.py field DIR                      DIR/0/U from DIR/0/C (the cell centres
                                                       OpenFOAM's writeCellCentres wrote)
  python3 bench/foam.py steps DIR N                    sets endTime to N steps, no write
  python3 bench/foam.py run LOG CMD...                 runs CMD (stdout and stderr to LOG),
                                                       noting the wall time of each
                                                       `ExecutionTime` line in LOG.wall;
                                                       prints CMD's CPU seconds (user + sys)
  python3 bench/foam.py rate LOG N SKIP                "CPU_RATE WALL_RATE STEPS": N particles
                                                       × the steps after the first SKIP /
                                                       their time, from OpenFOAM's
                                                       ExecutionTime (CPU) and LOG.wall
  python3 bench/foam.py compare DIR TIME CSV N CSV2    the physics check: OpenFOAM's parcels
                                                       at TIME against scg's frame CSV (N
                                                       particles at the start); CSV2: scg
                                                       with Stokes drag (the scale)
  python3 bench/foam.py params                         the case's parameters, one per line

The case: a box (x, y in [−W, W], z in [0, H]) of NX × NX × NZ hexahedra (blockMesh) or
of tetrahedra (crates/scg-mesh/examples/write_box_mesh.rs) holding a frozen steady flow
sampled at the cell centres: the paper's vortex about the z axis (ω = 31.4
rad/s, inflow ratio k = 0.1: u_θ = ω·r, u_r = −k·ω·r) plus an axial flow
u_z = W0·(1 − r²/R0²). The side faces are the wall patch `walls` (particles rebound
elastically), the top face the patch `outlet` and the bottom face the patch `inlet`
(particles crossing either leave). N particles
(d = 20 µm, ρ = 2500 kg/m³, starting at U0 = (0.1, 0, 0.2) m/s: stopping
distances 0.3 and 0.6 mm, so that some rebound from the wall x = W and some leave) uniformly at random in the cylinder r < 0.9·W,
0.05·H < z < 0.95·H, sorted by their cell (the same memory order for both codes).
"""
import math
import os
import random
import re
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))

W, H = 1.0e-3, 5.0e-3          # half-width in x, y and height, m
NX, NZ = 40, 100               # 40 × 40 × 100 = 160 000 hexahedra (50 µm cubes)
OMEGA, K = 31.4, 0.1           # the paper's vortex
W0, R0 = 0.01, 1.0e-3          # axial flow, m/s, and its radius
D, RHO_P = 20.0e-6, 2500.0     # particles
U0 = (0.1, 0.0, 0.2)           # their initial velocity, m/s (some reach the wall x = W or the outlet)
RHO_F, NU = 1.2, 1.5e-5        # fluid: mu = 1.8e-5 Pa s
DT = 1.0e-5


def flow(x, y, z):
    r2 = x * x + y * y
    return (-OMEGA * y - K * OMEGA * x, OMEGA * x - K * OMEGA * y, W0 * (1.0 - r2 / (R0 * R0)))


def cell_of(x, y, z):
    h = 2.0 * W / NX
    i = min(NX - 1, int((x + W) / h))
    j = min(NX - 1, int((y + W) / h))
    k = min(NZ - 1, int(z / (H / NZ)))
    return (k * NX + j) * NX + i  # blockMesh's order: x fastest, then y, then z


def header(cls, location, obj):
    return (
        "FoamFile\n{\n    version     2.0;\n    format      ascii;\n"
        f"    class       {cls};\n    location    \"{location}\";\n    object      {obj};\n}}\n\n"
    )


def fill(text, subs):
    for k, v in subs.items():
        text = text.replace(f"@{k}@", str(v))
    left = re.findall(r"@[A-Z_]+@", text)
    if left:
        sys.exit(f"unfilled template keys {left}")
    return text


def set_steps(case, steps, write_every):
    path = os.path.join(case, "system", "controlDict")
    with open(os.path.join(HERE, "openfoam", "system", "controlDict")) as f:
        text = f.read()
    with open(path, "w") as f:
        f.write(fill(text, {"END_TIME": repr(steps * DT), "DT": repr(DT), "WRITE_EVERY": write_every}))


def make_case(case, n, steps, seed, interp):
    subs = {
        "W": repr(W * 1e3), "H": repr(H * 1e3), "NX": NX, "NZ": NZ,
        "RHO_P": RHO_P, "RHO_F": RHO_F, "NU": NU, "MU": repr(RHO_F * NU), "D": repr(D), "U0": "%r %r %r" % U0,
    }
    for sub in ("system", "constant"):
        os.makedirs(os.path.join(case, sub), exist_ok=True)
        for name in os.listdir(os.path.join(HERE, "openfoam", sub)):
            if name == "controlDict":
                continue
            with open(os.path.join(HERE, "openfoam", sub, name)) as f:
                text = f.read()
            with open(os.path.join(case, sub, name), "w") as f:
                f.write(fill(text, subs))
    set_steps(case, steps, steps)
    # Positions: uniform in the cylinder, sorted by cell.
    rng = random.Random(seed)
    ps = []
    while len(ps) < n:
        r = 0.9 * W * math.sqrt(rng.random())
        t = 2.0 * math.pi * rng.random()
        z = H * (0.05 + 0.9 * rng.random())
        ps.append((r * math.cos(t), r * math.sin(t), z))
    ps.sort(key=lambda p: cell_of(*p))
    with open(os.path.join(case, "constant", "kinematicCloudPositions"), "w") as f:
        f.write(header("vectorField", "constant", "kinematicCloudPositions"))
        f.write(f"{n}\n(\n")
        f.writelines("(%.17g %.17g %.17g)\n" % p for p in ps)
        f.write(")\n")
    # scg runs one step more: OpenFOAM v1912 moves a parcel twice in the step that injects
    # it (once when injecting, once with the cloud), so its step n is scg's step n + 1.
    pos = ",\n".join("[%.17g, %.17g, %.17g]" % p for p in ps)
    with open(os.path.join(case, "scene.toml"), "w") as f:
        f.write(
            f'name = "vs-openfoam"\nduration = {(steps + 1) * DT!r}\ndt = {DT!r}\n'
            f"record_every = {steps + 1}\n"
            f"[fluid]\ndensity = {RHO_F}\nviscosity = {RHO_F * NU!r}\n"
            '[drag]\nlaw = "schiller_naumann"\n'
            f'[flow]\nkind = "openfoam"\ncase = "."\ntime = 0\nfield = "U"\n'
            f'interpolation = "{interp}"\n'
            '[flow.patches]\nwalls = ["walls"]\noutlets = ["outlet"]\n'
            f'[[groups]]\nname = "p"\ndiameter = {D!r}\ndensity = {RHO_P}\n'
            f"velocity = [{U0[0]!r}, {U0[1]!r}, {U0[2]!r}]\n"
            f"positions = [\n{pos}\n]\n"
        )


def write_field(case):
    """0/U: the flow at the cell centres that OpenFOAM wrote to 0/C (`postProcess -func
    writeCellCentres -time 0`), in the mesh's cell order; zeroGradient on every patch."""
    cc = foam_list(os.path.join(case, "0", "C"), vec)
    with open(os.path.join(case, "0", "U"), "w") as f:
        f.write(header("volVectorField", "0", "U"))
        f.write("dimensions      [0 1 -1 0 0 0 0];\n\n")
        f.write(f"internalField   nonuniform List<vector>\n{len(cc)}\n(\n")
        f.writelines("(%.17g %.17g %.17g)\n" % flow(*c) for c in cc)
        f.write(');\n\nboundaryField\n{\n    ".*" { type zeroGradient; }\n}\n')
    for name in ("C", "Cx", "Cy", "Cz"):
        p = os.path.join(case, "0", name)
        if os.path.exists(p):
            os.remove(p)
    print(len(cc))


def foam_list(path, parse):
    """The entries of an ASCII OpenFOAM list file (`N ( ... )`), one per line."""
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines) and not re.fullmatch(r"\s*\d+\s*", lines[i]):
        if re.fullmatch(r"\s*\d+\s*\(.*\)\s*", lines[i]):  # N(...) on one line
            return []
        i += 1
    n = int(lines[i])
    return [parse(ln) for ln in lines[i + 2:i + 2 + n]]


def vec(ln):
    return tuple(map(float, ln.split(")")[0].strip("( ").split()))


def read_foam(case, time):
    d = os.path.join(case, time, "lagrangian", "kinematicCloud")
    if not os.path.isdir(d):
        return {}
    pos = foam_list(os.path.join(d, "positions"), vec)
    u = foam_list(os.path.join(d, "U"), vec)
    ids = foam_list(os.path.join(d, "origId"), lambda ln: int(ln))
    return {i: (p, v) for i, p, v in zip(ids, pos, u)}


def read_scg(path):
    out = {}
    with open(path) as f:
        head = f.readline().strip().split(",")
        ix = head.index("x")
        for ln in f:
            c = ln.split(",")
            out[int(c[0])] = (tuple(map(float, c[ix:ix + 3])), tuple(map(float, c[ix + 3:ix + 6])))
    return out


def diffs(a, b):
    """Mean and max position and velocity differences over the ids in both, and the mean
    speed of b."""
    both = sorted(set(a) & set(b))
    dx = [math.dist(a[i][0], b[i][0]) for i in both]
    dv = [math.dist(a[i][1], b[i][1]) for i in both]
    sp = sum(math.hypot(*b[i][1]) for i in both) / len(both)
    return len(both), sum(dx) / len(dx), max(dx), sum(dv) / len(dv), max(dv), sp


def compare(case, time, csv, n, csv_stokes):
    """Prints the agreement; exits 1 when it is worse than the limits below. `csv_stokes`:
    scg's run with Stokes drag instead of Schiller–Naumann, the scale of what the choice
    of drag correlation alone does to this run."""
    fo, sc, st = read_foam(case, time), read_scg(csv), read_scg(csv_stokes)
    nb, dxm, dxx, dvm, dvx, sp_s = diffs(fo, sc)
    sp_f = diffs(sc, fo)[5]
    h = 2.0 * W / NX
    print(f"  particles in the box: OpenFOAM {len(fo)}, scg {len(sc)} (of {n}); in both {nb}")
    print(f"  position difference: mean {dxm / h:.3e}, max {dxx / h:.3e} h "
          f"(h = {h * 1e6:g} µm, the hex cell; {dxm / (2 * W):.3e}, {dxx / (2 * W):.3e} of the box width)")
    print(f"  velocity difference: mean {dvm / sp_s:.3e}, max {dvx / sp_s:.3e} of the mean speed "
          f"(OpenFOAM {sp_f:.6e}, scg {sp_s:.6e} m/s)")
    both = sorted(set(fo) & set(sc))
    for k, name in ((0, "x"), (2, "z")):
        mf = sum(fo[i][0][k] for i in both) / nb
        ms = sum(sc[i][0][k] for i in both) / nb
        print(f"  mean {name}: OpenFOAM {mf:.6e}, scg {ms:.6e} m (difference {(mf - ms) / h:+.2e} h)")
    _, sxm, sxx, svm, _, _ = diffs(st, sc)
    print(f"  scale: scg with Stokes drag instead of Schiller-Naumann moves by {sxm / h:.3e} (mean), "
          f"{sxx / h:.3e} (max) h, its velocity by {svm / sp_s:.3e} (mean); "
          f"OpenFOAM - scg is {dxm / sxm:.3f} of it")
    print("    (sphereDrag's Cd·Re/24 = 1 + Re^(2/3)/6 lies above Schiller-Naumann's "
          "1 + 0.15·Re^0.687 by about a tenth of the latter's correction)")
    ok = {
        f"counts differ by at most 0.1 % of {n}": abs(len(fo) - len(sc)) <= max(1, n // 1000)
        and nb >= min(len(fo), len(sc)) - max(1, n // 1000),
        "mean position difference < 0.1 h": dxm < 0.1 * h,
        "max position difference < 1 h": dxx < h,
        "mean velocity difference < 1 % of the mean speed": dvm < 0.01 * sp_s,
        "mean speeds within 1 %": abs(sp_f - sp_s) < 0.01 * sp_s,
        "OpenFOAM - scg below 1/4 of Stokes - Schiller-Naumann (mean position)": dxm < 0.25 * sxm,
    }
    for k, v in ok.items():
        print(f"  {k}: {'ok' if v else 'FAIL'}")
    sys.exit(0 if all(ok.values()) else 1)


def run(log, cmd):
    t0 = time.monotonic()
    with open(log, "w") as f, open(log + ".wall", "w") as w:
        p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        for ln in p.stdout:  # OpenFOAM flushes every line (std::endl)
            if ln.startswith("ExecutionTime"):
                w.write(f"{time.monotonic() - t0:.6f}\n")
            f.write(ln)
        rc = p.wait()
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    print(f"{ru.ru_utime + ru.ru_stime:.4f}")
    sys.exit(rc)


def rate(log, n, skip):
    """Particle-steps/s from the `ExecutionTime = ... s` lines of an OpenFOAM log (the
    process's CPU time, printed after every step) and from their wall times (LOG.wall):
    the steps after the first `skip` (start-up, injection, first location excluded)."""
    cpu = []
    with open(log) as f:
        for ln in f:
            m = re.match(r"ExecutionTime = ([0-9.eE+-]+) s", ln)
            if m:
                cpu.append(float(m.group(1)))
    with open(log + ".wall") as f:
        wall = [float(x) for x in f.read().split()]
    if len(cpu) <= skip + 1 or len(wall) != len(cpu):
        sys.exit(f"{log}: {len(cpu)} ExecutionTime lines ({len(wall)} timed), need more "
                 f"than {skip + 1}")
    steps = len(cpu) - 1 - skip
    print(f"{n * steps / (cpu[-1] - cpu[skip]):.4e} {n * steps / (wall[-1] - wall[skip]):.4e} {steps}")


def main(argv):
    cmd = argv[1]
    if cmd == "case":
        make_case(argv[2], int(argv[3]), int(argv[4]), int(argv[5]), argv[6])
    elif cmd == "field":
        write_field(argv[2])
    elif cmd == "steps":
        set_steps(argv[2], int(argv[3]), 10 * int(argv[3]) + 10)
    elif cmd == "run":
        run(argv[2], argv[3:])
    elif cmd == "rate":
        rate(argv[2], int(argv[3]), int(argv[4]))
    elif cmd == "compare":
        compare(argv[2], argv[3], argv[4], int(argv[5]), argv[6])
    elif cmd == "params":
        tau = RHO_P * D * D / (18.0 * RHO_F * NU)
        print(f"box {2 * W:g} x {2 * W:g} x {H:g} m; hex: {NX} x {NX} x {NZ} hexahedra "
              f"({NX * NX * NZ} cells of {2 * W / NX:g} m); tet: 20 x 20 x 67 hexahedra x 6")
        print(f"flow: vortex about z, omega = {OMEGA} rad/s, inflow ratio {K}, "
              f"axial u_z = {W0}*(1 - r^2/{R0:g}^2) m/s; fluid rho = {RHO_F}, mu = {RHO_F * NU:g}")
        print(f"particles: d = {D:g} m, rho = {RHO_P}, initial velocity {U0} m/s; tau = {tau:.3e} s; dt = {DT:g} s")
    else:
        sys.exit(f"unknown command {cmd}")


if __name__ == "__main__":
    main(sys.argv)
