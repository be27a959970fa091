#!/usr/bin/env python3
"""Where along the elbow each code puts the wear: OpenFOAM's ParticleErosion against scg's
--erosion-csv, by position along the pipe (cases/elbow.toml's geometry).

    python3 cases/elbow/bend.py OF_TIME_DIR CENTRES SCG_CSV [--bin DEG] [--json OUT]

OF_TIME_DIR: the OpenFOAM case's last time folder (its kinematicCloudQ); CENTRES: a C
field (postProcess -func writeCellCentres: the wall faces' centres); SCG_CSV: scg run
--erosion-csv. Each wall face goes to a zone: --leg-bin mm (default 50) of the inlet leg
(x < 0) or the outlet leg (y > R), counted from the bend, or the bend at angle
theta = atan2(x, R - y) (0 where the bend starts, 90 where it ends; bins of --bin
degrees, default 30), on its outer half (farther than R from the
bend's axis, the extrados) or its inner half. Prints each zone's share of each code's
total and the zone, and the angle of the face, where each code's wear is largest.
No OpenFOAM needed to run it (the unit test feeds it small files).
"""
import argparse
import csv
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "squarebend"))
import vs_openfoam as sq  # noqa: E402  (the squareBend side by side: OpenFOAM field lists)

R = 0.075      # bend radius to the pipe axis, m (cases/elbow/blockmesh.py)


LEG = 0.3      # length of each straight leg, m


def leg_bins(leg_bin):
    """The legs' zone names' ranges, from the bend: "0-50 mm", …"""
    n = int(round(LEG / leg_bin))
    return [f"{k * leg_bin * 1e3:g}-{(k + 1) * leg_bin * 1e3:g} mm" for k in range(n)]


def zone(c, width, leg_bin=0.05):
    """(name, angle or None) of a face centre c = (x, y, z)."""
    x, y, _ = c
    if x < 0.0 or y > R:
        # along the leg from the bend: 0 at the bend's end
        s = -x if x < 0.0 else y - R
        bins = leg_bins(leg_bin)
        k = min(int(s / leg_bin * (1 + 1e-12)), len(bins) - 1)
        return f"{'inlet' if x < 0.0 else 'outlet'} leg {bins[k]}", None
    theta = math.degrees(math.atan2(x, R - y))
    side = "outer" if math.hypot(x, R - y) > R else "inner"
    lo = min(int(theta // width) * width, 90 - width)
    return f"bend {side} {lo:g}-{lo + width:g}°", theta


def wear(of_time_dir, centres, scg_csv, patch="walls"):
    """[(centre, volume)] of each code's wall faces."""
    q = sq._foam_list(os.path.join(of_time_dir, "kinematicCloudQ"), patch, "scalar")
    c = sq._foam_list(centres, patch, "vector")
    if len(q) != len(c):
        sys.exit(f"bend.py: {len(q)} Q values but {len(c)} face centres on {patch}")
    of = [(ci, qi) for ci, qi in zip(c, q) if qi > 0]
    with open(scg_csv) as f:
        sc = [((float(r["x"]), float(r["y"]), float(r["z"])), float(r["volume_m3"]))
              for r in csv.DictReader(f) if r["patch"] == patch]
    return of, sc


def table(of, sc, width, leg_bin=0.05):
    """The zones' shares of each code's total and where each code's largest face is."""
    zones = {}
    totals = []
    for k, faces in enumerate((of, sc)):
        total = sum(v for _, v in faces)
        if total <= 0:
            sys.exit("bend.py: a code removed nothing: no wear to compare")
        totals.append(total)
        for c, v in faces:
            zones.setdefault(zone(c, width, leg_bin)[0], [0.0, 0.0])[k] += v / total
    legs = leg_bins(leg_bin)
    order = ([f"inlet leg {b}" for b in reversed(legs)]
             + [f"bend {s} {lo:g}-{lo + width:g}°" for s in ("outer", "inner")
                for lo in range(0, 90, int(width))]
             + [f"outlet leg {b}" for b in legs])
    rows = [(z, *zones.get(z, (0.0, 0.0))) for z in order]
    deepest = []
    for faces in (of, sc):
        c, v = max(faces, key=lambda cv: cv[1])
        name, theta = zone(c, width, leg_bin)
        deepest.append({"centre": list(c), "volume": v, "zone": name, "angle": theta})
    top = [max(rows, key=lambda r: r[1])[0], max(rows, key=lambda r: r[2])[0]]
    return {"bin_deg": width, "leg_bin_mm": leg_bin * 1e3, "openfoam_total": totals[0], "scg_total": totals[1],
            "zones": [{"zone": z, "openfoam": a, "scg": b} for z, a, b in rows],
            "openfoam_top_zone": top[0], "scg_top_zone": top[1],
            "openfoam_deepest": deepest[0], "scg_deepest": deepest[1]}


def render(t):
    lines = [f"wear along the elbow (share of each code's total; bend bins of {t['bin_deg']:g}°, "
             f"leg bins of {t['leg_bin_mm']:g} mm from the bend)",
             f"  total: OpenFOAM {t['openfoam_total']:.4e} m³, scg {t['scg_total']:.4e} m³",
             "  zone                      OpenFOAM     scg"]
    for z in t["zones"]:
        if z["openfoam"] or z["scg"]:
            lines.append(f"  {z['zone']:<24} {z['openfoam']:9.3f} {z['scg']:8.3f}")
    lines.append(f"  most wear: OpenFOAM in {t['openfoam_top_zone']}, scg in {t['scg_top_zone']}"
                 f" ({'same' if t['openfoam_top_zone'] == t['scg_top_zone'] else 'different'})")
    for who in ("openfoam", "scg"):
        d = t[f"{who}_deepest"]
        where = d["zone"] + (f", θ = {d['angle']:.1f}°" if d["angle"] is not None else "")
        lines.append(f"  deepest face ({'OpenFOAM' if who == 'openfoam' else 'scg'}): "
                     f"{' '.join(f'{x * 1e3:.1f}' for x in d['centre'])} mm ({where})")
    return "\n".join(lines) + "\n"


def main(argv):
    ap = argparse.ArgumentParser(prog="bend.py", description=__doc__.split("\n")[0])
    ap.add_argument("of_time_dir")
    ap.add_argument("centres")
    ap.add_argument("scg_csv")
    ap.add_argument("--bin", type=float, default=30.0, help="bend zones, degrees (divides 90)")
    ap.add_argument("--leg-bin", type=float, default=50.0, help="leg zones, mm along the pipe")
    ap.add_argument("--json")
    a = ap.parse_args(argv[1:])
    if not 0 < a.bin <= 90 or 90 % a.bin:
        sys.exit("bend.py: --bin must divide 90")
    t = table(*wear(a.of_time_dir, a.centres, a.scg_csv), a.bin, a.leg_bin / 1e3)
    print(render(t), end="")
    if a.json:
        with open(a.json, "w") as f:
            json.dump(t, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
