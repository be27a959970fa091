"""Helpers of cases/squarebend/vs-openfoam.sh: the fates of the particles in OpenFOAM's
squareBend duct, per size class, in OpenFOAM's uncoupledKinematicParcelFoam and in scg,
with binomial 95 % (Wilson) intervals. Python 3.11+ standard library. The scene -> OpenFOAM
case mapping and OpenFOAM's results (`case`, `grade`) are cases/cyclone/vs_openfoam.py's,
imported: this file reads their grade.json and scg's `run --summary-json` file.

  python3 vs_openfoam.py openfoam GRADE.json [--json OUT]
      OpenFOAM's table alone (fed, outlet, inlet, walls, airborne per class)
  python3 vs_openfoam.py table GRADE.json SCG.json [--json OUT]
      both codes side by side, per class and fate: counts, fractions, 95 % intervals and
      whether the two intervals overlap

Fates: `outlet` = escaped through the outlet patch(es), `inlet` = escaped through the
inlet patch(es) (blown back out), `walls` = stuck on the wall patch(es), `airborne` =
still in the duct and moving at the end (fed minus the others).

scg's summary is read generically: per group (and its `fates` table, when there is one,
as written by scg's per-patch fates: `patches` = [{patch, role, escaped, stuck, ...}],
`airborne`) `fed`, and the per-patch counts from the
first key among PATCH_KEYS holding a table by patch name (a count, a table of fates
with counts, or a list of times per patch), else `drained` (outlets), `lost` (inlets)
and a stuck count from STUCK_KEYS. When the walls' count is not found the table says so
and prints the keys the summary has.
"""
import json
import math
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def _load_cyclone():
    """cases/cyclone/vs_openfoam.py (case, grade) under its own module name: this file has
    the same name."""
    import importlib.util
    name = "cyclone_vs_openfoam"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, os.path.join(HERE, "..", "cyclone", "vs_openfoam.py"))
    mod = importlib.util.module_from_spec(spec)
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


cyc = _load_cyclone()

FATES = ("outlet", "inlet", "walls", "airborne")
PATCH_KEYS = ("patches", "patch_fates", "fates", "per_patch", "by_patch", "patch_counts")
STUCK_KEYS = ("stuck", "stuck_walls", "stick", "held_walls", "deposited", "walls")
AIRBORNE_KEYS = ("airborne", "held_airborne", "moving", "suspended")
Z95 = 1.959963984540054


def wilson(k, n, z=Z95):
    """The Wilson score interval (lo, hi) of a binomial fraction k/n; (None, None) if n = 0."""
    if not n:
        return None, None
    p = k / n
    den = 1.0 + z * z / n
    mid = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    return (0.0 if k == 0 else max(0.0, mid - half)), (1.0 if k == n else min(1.0, mid + half))


def overlap(a, b):
    """Whether two intervals (lo, hi) overlap; None when one is unknown."""
    if None in a or None in b:
        return None
    return a[0] <= b[1] and b[0] <= a[1]


def _count(v):
    """A count from a summary value: an int, a list (of times), or a table of fates or
    with a count."""
    if isinstance(v, bool):
        return None
    if isinstance(v, int):
        return v
    if isinstance(v, float) and v.is_integer():
        return int(v)
    if isinstance(v, list):
        return len(v)
    if isinstance(v, dict):
        for k in ("count", "n", "number", "total"):
            if k in v:
                return _count(v[k])
        parts = [_count(x) for k, x in v.items()
                 if not k.endswith(("_mass", "_times")) and k not in ("role", "patch", "fate", "model")]
        parts = [x for x in parts if x is not None]
        return sum(parts) if parts else None
    return None


def _patch_table(g, names):
    """{patch: count} from the first of PATCH_KEYS that holds a table (or a list of rows
    with `patch`) naming at least one of the mesh's patches `names`; None if none does."""
    for key in PATCH_KEYS:
        v = g.get(key)
        if isinstance(v, list) and all(isinstance(r, dict) and "patch" in r for r in v):
            out = {}
            for r in v:
                rest = {k: x for k, x in r.items() if k not in ("patch", "fate", "model")}
                c = _count(rest) if rest else None
                out[r["patch"]] = out.get(r["patch"], 0) + (c or 0)
            if set(out) & names:
                return key, out
        if isinstance(v, dict) and set(v) & names:
            return key, {p: (_count(x) or 0) for p, x in v.items() if p in names}
        if isinstance(v, dict):  # by fate first: {"stuck": {"walls": 3}, "escaped": {...}}
            inner = {}
            for fate, x in v.items():
                if isinstance(x, dict) and set(x) & names:
                    for p, y in x.items():
                        if p in names:
                            inner[p] = inner.get(p, 0) + (_count(y) or 0)
            if inner:
                return key, inner
    return None, None


def scg_fates(summary, walls, outlets, inlets):
    """Per group {group, diameter, fed, outlet, inlet, walls, airborne, how} from scg's
    summary JSON; a fate is None when it cannot be read (`how` says what was used)."""
    names = set(walls) | set(outlets) | set(inlets)
    out = []
    for g0 in summary.get("groups", []):
        # a group's `fates` table (scg's per-patch fates) read as part of the group
        g = dict(g0, **g0["fates"]) if isinstance(g0.get("fates"), dict) else g0
        fed = int(g.get("fed", 0))
        key, table = _patch_table(g, names)
        how = []
        if table is not None:
            how.append(f"per patch from '{key}'")
            o = sum(table.get(p, 0) for p in outlets)
            i = sum(table.get(p, 0) for p in inlets)
            w = sum(table.get(p, 0) for p in walls)
        else:
            o = _count(g.get("drained"))
            i = _count(g.get("lost"))
            how.append("outlet = drained, inlet = lost")
            w = None
            for k in STUCK_KEYS:
                if k in g and _count(g[k]) is not None:
                    w = _count(g[k])
                    how.append(f"walls = {k}")
                    break
        a = None
        for k in AIRBORNE_KEYS:
            if k in g and _count(g[k]) is not None:
                a = _count(g[k])
                how.append(f"airborne = {k}")
                break
        rest = fed - o - i - w if None not in (o, i, w) else None
        if a is None and rest is not None:
            a = rest
            how.append("airborne = fed - outlet - inlet - walls")
            held = _count(g.get("held"))
            if held is not None and held not in (rest, rest + w):
                how.append(f"(held {held} is neither airborne {rest} nor airborne + walls {rest + w})")
        elif a is not None and rest is not None and a != rest:
            how.append(f"(fed - outlet - inlet - walls = {rest})")
        out.append({"group": g.get("group"), "diameter": g.get("diameter"), "fed": fed,
                    "outlet": o, "inlet": i, "walls": w, "airborne": a, "how": "; ".join(how)})
    return out


def openfoam_fates(grade, inlets=None):
    """Per class {group, diameter, fed, outlet, inlet, walls, airborne} from grade.json
    (cases/cyclone/vs_openfoam.py grade): escaped = outlet, lost = inlet (and other escape
    patches: `other`), stuck = walls, held = airborne."""
    out = []
    for c in grade["classes"]:
        lost = c.get("lost", 0)
        inlet = lost
        if inlets is not None and "patches" in c:
            inlet = sum(c["patches"].get(p, 0) for p in inlets)
        out.append({"group": c["group"], "diameter": c["diameter"], "fed": c["fed"],
                    "outlet": c["escaped"], "inlet": inlet, "other": lost - inlet,
                    "walls": c.get("stuck", 0), "airborne": c["held"]})
    return out


def _cell(k, n):
    if k is None or not n:
        return f"{'?':>5} {'':>6} {'':>15}", (None, None)
    lo, hi = wilson(k, n)
    return f"{k:5d} {k / n:6.3f} [{lo:5.3f}, {hi:5.3f}]", (lo, hi)


def openfoam_table(grade_path, dest=None):
    g = cyc.read_json(grade_path)
    fo = openfoam_fates(g)
    print("OpenFOAM uncoupledKinematicParcelFoam: fates per class (count, fraction of fed, "
          "95 % Wilson interval)")
    print(f"{'class':>6} {'d [µm]':>7} {'fed':>5} | " + " | ".join(f"{f:^28}" for f in FATES))
    for c in fo:
        cells = [_cell(c[f], c["fed"])[0] for f in FATES]
        print(f"{c['group']:>6} {c['diameter'] * 1e6:7.3g} {c['fed']:5d} | " + " | ".join(cells))
    if g.get("log_fates"):
        print("OpenFOAM log, localInteraction per patch (all classes): " + "; ".join(
            f"{p} " + ", ".join(f"{k} {v}" for k, v in sorted(f.items())) for p, f in sorted(g["log_fates"].items())))
    if dest:
        cyc.write_json(dest, {"openfoam": fo})
    return fo


def table(grade_path, scg_path, walls, outlets, inlets, dest=None):
    """The side-by-side table; returns (rows, all_overlap)."""
    g = cyc.read_json(grade_path)
    s = cyc.read_json(scg_path)
    fo = {c["group"]: c for c in openfoam_fates(g, inlets)}
    sc = scg_fates(s, walls, outlets, inlets)
    rows, all_ok, unknown = [], True, False
    for c in sc:
        f = fo.get(c["group"])
        if f is None:
            print(f"class {c['group']}: not in OpenFOAM's grade.json ({sorted(fo)})")
            all_ok = False
            continue
        print(f"\n== class {c['group']}, d = {c['diameter'] * 1e6:.3g} µm: fed OpenFOAM {f['fed']}, scg {c['fed']}")
        print(f"{'fate':>9} | {'OpenFOAM':^28} | {'scg':^28} | overlap")
        for fate in FATES:
            a, ia = _cell(f[fate], f["fed"])
            b, ib = _cell(c[fate], c["fed"])
            ov = overlap(ia, ib)
            if ov is None:
                unknown = True
            elif not ov:
                all_ok = False
            print(f"{fate:>9} | {a} | {b} | {'-' if ov is None else 'yes' if ov else 'NO'}")
            rows.append({"group": c["group"], "fate": fate, "openfoam": f[fate], "openfoam_fed": f["fed"],
                         "openfoam_ci": ia, "scg": c[fate], "scg_fed": c["fed"], "scg_ci": ib, "overlap": ov})
        print(f"  scg read: {c['how']}")
    if unknown:
        keys = sorted({k for gr in s.get("groups", []) for k in gr})
        print(f"\nscg's summary lacks a per-patch count (walls); its group keys: {', '.join(keys)}; "
              f"top-level keys: {', '.join(sorted(s))}")
    print("\nfractions of the fed; [lo, hi]: binomial 95 % Wilson interval; overlap: the two intervals overlap")
    verdict = "unknown (missing counts)" if unknown and all_ok else "yes" if all_ok else "NO"
    print(f"all intervals overlap: {verdict}")
    if dest:
        cyc.write_json(dest, {"rows": rows, "all_overlap": None if unknown and all_ok else all_ok,
                              "openfoam": list(fo.values()), "scg": sc})
    return rows, (None if unknown and all_ok else all_ok)


def _foam_list(path, patch, kind):
    """The values of `patch` in an ASCII OpenFOAM field file: scalars (kind "scalar") or
    vectors, in the patch's face order (a uniform value gives an empty list)."""
    text = cyc.read_text(path)
    m = re.search(r"\n\s*" + re.escape(patch) + r"\s*\{(.*?)\n\s*\}", text, re.S)
    if not m:
        sys.exit(f"{path}: no patch {patch}")
    body = m.group(1)
    v = re.search(r"nonuniform\s+List<\w+>\s*(\d+)\s*\((.*)\)\s*;", body, re.S)
    if not v:
        return []
    n, data = int(v.group(1)), v.group(2)
    if kind == "scalar":
        out = [float(x) for x in data.split()]
    else:
        out = [tuple(float(x) for x in t.split()) for t in re.findall(r"\(([^()]*)\)", data)]
    if len(out) != n:
        sys.exit(f"{path}: {patch} lists {len(out)} values for {n}")
    return out


def erosion(of_time_dir, centres_file, patches, scg_csv, region, dest=None):
    """Side by side of the eroded volume: OpenFOAM's ParticleErosion field (Q on the
    patches at the end) against scg's --erosion-csv, both summed into cubic regions of
    `region` m; the regions' shares of the total, the deepest face of each code and
    whether both put the most wear in the same region."""
    import csv
    import math
    cells = {}
    of_total, of_max = 0.0, (0.0, None)
    for p in patches:
        q = _foam_list(os.path.join(of_time_dir, "kinematicCloudQ"), p, "scalar")
        c = _foam_list(centres_file, p, "vector")
        for qi, ci in zip(q, c):
            if qi <= 0:
                continue
            key = tuple(math.floor(x / region) for x in ci)
            cells.setdefault(key, [0.0, 0.0])[0] += qi
            of_total += qi
            if qi > of_max[0]:
                of_max = (qi, ci)
    scg_total, scg_max = 0.0, (0.0, None)
    with open(scg_csv) as f:
        for r in csv.DictReader(f):
            if r["patch"] not in patches:
                continue
            qi = float(r["volume_m3"])
            ci = (float(r["x"]), float(r["y"]), float(r["z"]))
            key = tuple(math.floor(x / region) for x in ci)
            cells.setdefault(key, [0.0, 0.0])[1] += qi
            scg_total += qi
            if qi > scg_max[0]:
                scg_max = (qi, ci)
    if of_total <= 0 or scg_total <= 0:
        sys.exit(f"erosion: OpenFOAM total {of_total:g}, scg total {scg_total:g}: nothing to compare")
    rows = sorted(cells.items(), key=lambda kv: -(kv[1][0] / of_total + kv[1][1] / scg_total))
    lines = [f"erosion (Finnie), regions of {region * 1e3:g} mm: share of each code's total",
             f"  total volume removed: OpenFOAM {of_total:.4e} m³, scg {scg_total:.4e} m³ "
             f"(ratio {scg_total / of_total:.3f})",
             "  region centre [mm]            OpenFOAM    scg"]
    for key, (a, b) in rows[:8]:
        ctr = " ".join(f"{(k + 0.5) * region * 1e3:7.1f}" for k in key)
        lines.append(f"  {ctr}      {a / of_total:8.3f} {b / scg_total:8.3f}")
    top_of = max(cells, key=lambda k: cells[k][0])
    top_scg = max(cells, key=lambda k: cells[k][1])
    d = math.dist(of_max[1], scg_max[1])
    lines.append(f"  most wear: OpenFOAM's region {'=' if top_of == top_scg else '!='} scg's; "
                 f"deepest faces {d * 1e3:.1f} mm apart (OpenFOAM at "
                 f"{' '.join(f'{x * 1e3:.1f}' for x in of_max[1])} mm, scg at "
                 f"{' '.join(f'{x * 1e3:.1f}' for x in scg_max[1])} mm)")
    text = "\n".join(lines) + "\n"
    print(text, end="")
    if dest:
        with open(dest, "w") as f:
            json.dump({"openfoam_total": of_total, "scg_total": scg_total, "region": region,
                       "same_region": top_of == top_scg, "deepest_distance": d,
                       "openfoam_deepest": list(of_max[1]), "scg_deepest": list(scg_max[1]),
                       "regions": [[list(k), v[0] / of_total, v[1] / scg_total] for k, v in rows]}, f, indent=1)
    return 0


def erosion_scene(path, dest, flow_stress, restitution):
    """The scene of `path` with its walls rebounding (e = `restitution`), Finnie's erosion
    on them (p = `flow_stress` Pa) and OpenFOAM's drag (`putnam`, its sphereDrag), written
    to `dest` for both codes."""
    s = cyc.read_toml(path)
    flow = s.setdefault("flow", {})
    patches = flow.setdefault("patches", {})
    patches["wall_model"] = "rebound"
    patches["restitution"] = float(restitution)
    s["erosion"] = {"model": "finnie", "flow_stress": float(flow_stress)}
    s.setdefault("drag", {})["law"] = "putnam"
    if "case" in flow and not os.path.isabs(flow["case"]):
        flow["case"] = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(path)), flow["case"]))
    with open(dest, "w", encoding="utf-8") as f:
        f.write(cyc.toml_dump(s))
    return dest


def main(argv):
    import argparse
    ap = argparse.ArgumentParser(prog="vs_openfoam.py")
    sub = ap.add_subparsers(dest="cmd", required=True)
    o = sub.add_parser("openfoam")
    o.add_argument("grade")
    o.add_argument("--json")
    t = sub.add_parser("table")
    t.add_argument("grade")
    t.add_argument("scg")
    t.add_argument("--plan", help="the OpenFOAM cases' plan.json (patch roles; default next to GRADE)")
    t.add_argument("--json")
    es = sub.add_parser("erosion-scene")
    es.add_argument("scene")
    es.add_argument("dest")
    es.add_argument("--flow-stress", type=float, default=1.0e9)
    es.add_argument("--restitution", type=float, default=0.8)
    e = sub.add_parser("erosion")
    e.add_argument("of_time_dir", help="the OpenFOAM case's last time folder (kinematicCloudQ)")
    e.add_argument("centres", help="a C field (postProcess -func writeCellCentres): face centres")
    e.add_argument("scg_csv", help="scg run --erosion-csv")
    e.add_argument("--patches", default="walls")
    e.add_argument("--region", type=float, default=0.0125, help="region edge, m")
    e.add_argument("--json")
    a = ap.parse_args(argv[1:])
    if a.cmd == "erosion-scene":
        print(erosion_scene(a.scene, a.dest, a.flow_stress, a.restitution))
        return 0
    if a.cmd == "erosion":
        return erosion(a.of_time_dir, a.centres, a.patches.split(","), a.scg_csv, a.region, a.json)
    if a.cmd == "openfoam":
        openfoam_table(a.grade, a.json)
        return 0
    plan_path = a.plan or os.path.join(os.path.dirname(os.path.abspath(a.grade)), "openfoam", "plan.json")
    if os.path.isfile(plan_path):
        plan = cyc.read_json(plan_path)
        walls, outlets, inlets = plan["walls"], plan["outlets"], plan["inlets"]
    else:
        walls, outlets, inlets = ["walls"], ["outlet"], ["inlet"]
    table(a.grade, a.scg, walls, outlets, inlets, a.json)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
