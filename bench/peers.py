"""Helpers of bench/vs-peers.sh (standard library only).

  python3 bench/peers.py dense-scene N STEPS           scg scene of `scg bench dense` (N
                                                        particles), STEPS steps, frames at
                                                        0 and STEPS
  python3 bench/peers.py collide-scene VT              scg scene of the two-sphere twin
  python3 bench/peers.py wall-scene                    scg scene of the oblique wall bounce
  python3 bench/peers.py wall FILE                     "VX Z VZ" of the sphere (scg frame CSV)
  python3 bench/peers.py state FILE                    "KE Z ZMEAN N" of a dense-bed state
                                                        (scg frame CSV or LAMMPS/LIGGGHTS
                                                        dump)
  python3 bench/peers.py collide FILE                  "VX0 VY0 VX1 VY1" of sphere 0 and 1
                                                        (scg frame CSV)
  python3 bench/peers.py tsuji E                       "GAMMA E_LAMMPS XGT": scg's damping
                                                        γ(e), the restitution to hand to
                                                        LAMMPS's `damping tsuji` so that its
                                                        α polynomial equals γ, and √(4G*/E*)
  python3 bench/peers.py hertz-history E V              "KN KT GN" of LAMMPS's pair
                                                        gran/hertz/history: Hertz's 4E*/3,
                                                        Mindlin's 8G*, and the damping γn that
                                                        gives restitution E head-on at V m/s
"""
import math
import sys

D, RHO, E, NU, REST, MU, DT = 1e-3, 2500.0, 1e8, 0.3, 0.9, 0.5, 1e-6
W = 40  # dense bed: particles per row
MATERIAL = (
    f"[material]\nyoungs_modulus = {E:e}\npoisson_ratio = {NU}\n"
    f"restitution = {REST}\nfriction = {MU}\n"
)


def dense_scene(n, steps):
    """The scene `scg bench dense` builds (crates/scg-cli/src/bench.rs), for STEPS steps."""
    layers = -(-n // (W * W))
    ps = []
    for k in range(layers):
        for j in range(W):
            for i in range(W):
                if len(ps) < n:
                    ps.append(((i + 0.5) * D, (j + 0.5) * D, (k + 0.5) * D))
    l = W * D
    lz = 4.0 * layers * D + 10.0 * D
    th = math.radians(26.0)
    pos = ", ".join(f"[{x:e}, {y:e}, {z:e}]" for x, y, z in ps)
    return (
        f'name = "check-dense"\nduration = {steps * DT:e}\ndt = {DT:e}\nseed = 7\n'
        f"record_every = {steps}\n"
        f"[gravity]\nacceleration = [{9.81 * math.sin(th):e}, 0.0, {-9.81 * math.cos(th):e}]\n"
        f"{MATERIAL}[contacts]\nskin = {0.1 * D:e}\nperiodic = [{l:e}, {l:e}, {lz:e}]\n"
        '[[walls]]\nname = "floor"\nkind = "plane"\npoint = [0.0, 0.0, 0.0]\n'
        "normal = [0.0, 0.0, 1.0]\n"
        f'[[groups]]\nname = "p"\ndiameter = {D:e}\ndensity = {RHO}\npositions = [{pos}]\n'
    )


def collide_scene(vt):
    """Two spheres 1 µm apart along x at ±(0.5, vt, 0) m/s, 200 steps (bench/*/in.collide)."""
    return (
        f'name = "check-collide"\nduration = {200 * DT:e}\ndt = {DT:e}\nrecord_every = 200\n'
        f"{MATERIAL}[contacts]\nskin = {0.1 * D:e}\n"
        f'[[groups]]\nname = "p"\ndiameter = {D:e}\ndensity = {RHO}\n'
        "positions = [[-5.005e-4, 0.0, 0.0], [5.005e-4, 0.0, 0.0]]\n"
        f"velocities = [[0.5, {vt}, 0.0], [-0.5, {-vt}, 0.0]]\n"
    )


def wall_scene():
    """One sphere 0.5 µm above the floor z = 0 at (0.5, 0, −1) m/s, 100 steps
    (bench/*/in.wall)."""
    return (
        f'name = "check-wall"\nduration = {100 * DT:e}\ndt = {DT:e}\nrecord_every = 100\n'
        f"{MATERIAL}"
        '[[walls]]\nname = "floor"\nkind = "plane"\npoint = [0.0, 0.0, 0.0]\n'
        "normal = [0.0, 0.0, 1.0]\n"
        f'[[groups]]\nname = "p"\ndiameter = {D:e}\ndensity = {RHO}\n'
        "positions = [[0.0, 0.0, 5.005e-4]]\nvelocities = [[0.5, 0.0, -1.0]]\n"
    )


def read_state(path):
    """Rows (id, x, y, z, vx, vy, vz) from an scg frame CSV or a LAMMPS/LIGGGHTS dump (its
    last snapshot)."""
    with open(path) as f:
        lines = f.read().splitlines()
    rows = []
    if lines and lines[0].startswith("id,group"):
        for ln in lines[1:]:
            c = ln.split(",")
            if len(c) >= 8:
                rows.append((int(c[0]), *map(float, c[2:8])))
        return rows
    start = max(i for i, ln in enumerate(lines) if ln.startswith("ITEM: ATOMS"))
    for ln in lines[start + 1:]:
        c = ln.split()
        rows.append((int(c[0]), *map(float, c[1:7])))
    return rows


def state(path):
    """Translational kinetic energy (J), coordination number (particle–particle contacts
    with an overlap above 1e-9 m, per particle; periodic in x and y with the bed's width),
    mean height (m) and count."""
    rows = read_state(path)
    n = len(rows)
    m = RHO * math.pi / 6.0 * D**3
    ke = sum(0.5 * m * (r[4] ** 2 + r[5] ** 2 + r[6] ** 2) for r in rows)
    zmean = sum(r[3] for r in rows) / n
    l = W * D
    cell = 1.2 * D
    nc = int(l / cell)
    cs = l / nc
    grid = {}
    pts = []
    for r in rows:
        x, y, z = r[1] % l, r[2] % l, r[3]
        key = (int(x / cs) % nc, int(y / cs) % nc, int(z / cs))
        grid.setdefault(key, []).append(len(pts))
        pts.append((x, y, z))
    contacts = 0
    cut2 = (D - 1e-9) ** 2
    for (cx, cy, cz), members in grid.items():
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    other = grid.get(((cx + dx) % nc, (cy + dy) % nc, cz + dz))
                    if not other:
                        continue
                    for a in members:
                        xa, ya, za = pts[a]
                        for b in other:
                            if b <= a:
                                continue
                            xb, yb, zb = pts[b]
                            ddx = (xb - xa + l / 2) % l - l / 2
                            ddy = (yb - ya + l / 2) % l - l / 2
                            ddz = zb - za
                            if ddx * ddx + ddy * ddy + ddz * ddz < cut2:
                                contacts += 1
    return ke, 2.0 * contacts / n, zmean, n


def tsuji(e):
    """scg's γ(e) = √5·|ln e|/√(ln²e + π²); the e' whose LAMMPS Tsuji polynomial α(e')
    equals it; and the tangential/normal damping ratio √(4G*/E*) of scg's dashpots."""
    lg = math.log(e)
    gamma = math.sqrt(5.0) * abs(lg) / math.sqrt(lg * lg + math.pi**2)

    def alpha(x):  # LAMMPS pair granular, damping tsuji
        return (1.2728 - 4.2783 * x + 11.087 * x**2 - 22.348 * x**3 + 27.467 * x**4
                - 18.022 * x**5 + 4.8218 * x**6)

    lo, hi = 0.05, 0.999  # α decreases on this interval
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if alpha(mid) > gamma:
            lo = mid
        else:
            hi = mid
    e_star = E / (2.0 * (1.0 - NU * NU))
    g = E / (2.0 * (1.0 + NU))
    g_star = 1.0 / (2.0 * (2.0 - NU) / g)
    return gamma, 0.5 * (lo + hi), math.sqrt(4.0 * g_star / e_star), alpha(e)


def hertz_history(e, v0):
    """LAMMPS's gran/hertz/history with scg's stiffness: kn = 4E*/3 (Hertz), kt = 8G*
    (Mindlin), and its damping m*·γn·v_n·√(R*δ) set (bisection on a head-on collision of two
    spheres, integrated at 1/2500 of the contact time) to give restitution `e` at `v0`;
    unlike Tsuji's damping its restitution grows as the impact slows."""
    e_star = E / (2.0 * (1.0 - NU * NU))
    g_star = (E / (2.0 * (1.0 + NU))) / (2.0 * (2.0 - NU))
    kn, kt = 4.0 / 3.0 * e_star, 8.0 * g_star
    m_eff, r_eff = RHO * math.pi / 6.0 * D**3 / 2.0, D / 4.0

    def restitution(g):
        x, v, dt = 0.0, v0, 2e-9 / v0 ** 0.2
        while True:
            v -= math.sqrt(r_eff * max(x, 0.0)) * (kn * x + m_eff * g * v) / m_eff * dt
            x += v * dt
            if x <= 0.0 and v < 0.0:
                return -v / v0

    lo, hi = 1.0, 1e12
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if restitution(mid) > e:
            lo = mid
        else:
            hi = mid
    return kn, kt, math.sqrt(lo * hi)


def main(argv):
    cmd = argv[1]
    if cmd == "dense-scene":
        sys.stdout.write(dense_scene(int(argv[2]), int(argv[3])))
    elif cmd == "collide-scene":
        sys.stdout.write(collide_scene(float(argv[2])))
    elif cmd == "wall-scene":
        sys.stdout.write(wall_scene())
    elif cmd == "wall":
        r = read_state(argv[2])[0]
        print(f"{r[4]:.10e} {r[3]:.10e} {r[6]:.10e}")
    elif cmd == "state":
        ke, z, zm, n = state(argv[2])
        print(f"{ke:.6e} {z:.5f} {zm:.6e} {n}")
    elif cmd == "collide":
        rows = sorted(read_state(argv[2]))
        print(f"{rows[0][4]:.10e} {rows[0][5]:.10e} {rows[1][4]:.10e} {rows[1][5]:.10e}")
    elif cmd == "tsuji":
        gamma, e_l, xgt, a_e = tsuji(float(argv[2]))
        print(f"{gamma:.17g} {e_l:.17g} {xgt:.17g} {a_e:.17g}")
    elif cmd == "hertz-history":
        kn, kt, gn = hertz_history(float(argv[2]), float(argv[3]))
        print(f"{kn:.17g} {kt:.17g} {gn:.17g}")
    else:
        sys.exit(f"unknown command {cmd}")


if __name__ == "__main__":
    main(sys.argv)
