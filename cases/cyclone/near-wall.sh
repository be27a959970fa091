#!/usr/bin/env bash
# The cyclone's grade efficiency under what decides it next to the walls and in the air:
# the interpolation (the scene's volume-conserving `conservative`, `cell_point` with or
# without the CFD's log law at the walls, `cell_value`), the turbulent dispersion (the
# scene's drift-corrected Langevin walk, OpenFOAM's stochastic eddy model, none), the wall
# rebound, and the dust-outlet trap's wait. Writes each variant of cases/cyclone.toml into
# --out, runs it for 6 s, prints η = collected/fed per class (the scene's `dust_outlet`
# zone) with Wilson's 95 % interval, and 1 − escaped/fed and the undecided share beside it.
#
#   bash cases/cyclone/near-wall.sh [--out DIR] [--feed-scale F] [--only NAMES] [--case DIR]
#
#   --case DIR  another build of the field (e.g. build.sh --full --layers 3 --out DIR)
#               instead of the committed cases/cyclone/coarse
#
# Variants (the scene: conservative, langevin, rebound e = 0.5 without friction, a trap
# that waits 0.1 s):
#   scene       the scene as committed
#   eddy        dispersion by the stochastic eddy model (stochastic_ras)
#   nodisp      no dispersion
#   cell_point  interpolation = cell_point (ramps to the no-slip walls)
#   wallfn      cell_point with the CFD's log law at the walls ([flow.wall_function])
#   cell_value  interpolation = cell_value
#   entry       the trap collects on entry (no wait)
#   e09, mu02, mu05, e09_mu05   the wall rebound: restitution 0.9 and/or friction 0.2, 0.5
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out=/tmp/scg-cyclone-near-wall
feed=1
only=""
case_dir=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --feed-scale) feed="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    --case) case_dir="$(cd "$2" && pwd)"; shift 2 ;;
    -h|--help) sed -n 2,24p "$0"; exit 0 ;;
    *) echo "near-wall.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
scg="$root/target/release/scg"
[ -x "$scg" ] || (cd "$root" && cargo build --release --quiet)
python3 - "$root" "$out" "${case_dir:-$root/cases/cyclone/coarse}" <<'PY'
import sys
root, out, case = sys.argv[1], sys.argv[2], sys.argv[3]
src = open(f"{root}/cases/cyclone.toml").read()
assert 'case = "cyclone/coarse"' in src, "cases/cyclone.toml: no case = \"cyclone/coarse\""
src = src.replace('case = "cyclone/coarse"', f'case = "{case}"')
interp = 'interpolation = "conservative"'
assert interp in src, "cases/cyclone.toml: no interpolation = \"conservative\""
line = next(l for l in src.splitlines() if l.startswith(interp))
disp = '[dispersion]\nmodel = "langevin"\n'
block = disp + 'k = "kMean"\nomega = "omegaMean"\n'
assert block in src, "cases/cyclone.toml has no langevin [dispersion] on kMean, omegaMean"
wait = "collects_after = 0.1"
assert wait in src, "cases/cyclone.toml: no collects_after = 0.1"
rebound = 'wall_model = "rebound"'
def walls(e=None, mu=None):
    extra = (f"\nrestitution = {e}" if e else "") + (f"\nfriction = {mu}" if mu else "")
    return src.replace(rebound, rebound + extra, 1)
v = {
    "scene": src,
    "eddy": src.replace(disp, '[dispersion]\nmodel = "stochastic_ras"\n'),
    "nodisp": src.replace(block, ""),
    "cell_point": src.replace(line, 'interpolation = "cell_point"'),
    "wallfn": src.replace(line, 'interpolation = "cell_point"\n\n[flow.wall_function]\nmodel = "log_law"\nk = "kMean"'),
    "cell_value": src.replace(line, 'interpolation = "cell_value"'),
    "entry": src.replace(wait, ""),
    "e09": walls(e=0.9),
    "mu02": walls(mu=0.2),
    "mu05": walls(mu=0.5),
    "e09_mu05": walls(e=0.9, mu=0.5),
}
for k, s in v.items():
    open(f"{out}/{k}.toml", "w").write(s)
PY
names="scene eddy nodisp cell_point wallfn cell_value entry e09 mu02 mu05 e09_mu05"
[ -n "$only" ] && names="${only//,/ }"
for k in $names; do
  [ -f "$out/$k.toml" ] || { echo "near-wall.sh: unknown variant $k" >&2; exit 2; }
  "$scg" run "$out/$k.toml" --set duration=6 --set "feed_scale=$feed" --no-record \
    --summary-json "$out/$k.json" > "$out/$k.log" 2>&1
done
python3 - "$out" $names <<'PY'
import json, math, sys
out, names = sys.argv[1], sys.argv[2:]
def wilson(k, n, z=1.96):
    p = k / n; d = 1 + z * z / n; c = (p + z * z / (2 * n)) / d
    h = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / d
    return max(c - h, 0.0), min(c + h, 1.0)
rows = {}
for k in names:
    d = json.load(open(f"{out}/{k}.json"))
    rows[k] = [(g["group"], g["fates"]["fed"], sum(p["escaped"] for p in g["fates"]["patches"] if p["role"] == "outlet")) for g in d["groups"]]
    rows[k + "/wall_s"] = d["wall_s"]
    rows[k + "/coll"] = [g["fates"].get("collected", 0) for g in d["groups"]]
groups = [g for g, _, _ in rows[names[0]]]
fed0 = rows[names[0]][0][1]
print(f"eta = collected/fed [95 % Wilson interval] | 1 - escaped/fed | undecided, %, 6 s, fed {fed0} per class")
print(f"{'class':<6}" + "".join(f"{k:>30}" for k in names))
for i, g in enumerate(groups):
    line = f"{g:<6}"
    for k in names:
        _, fed, esc = rows[k][i]
        c = rows[k + "/coll"][i]
        lo, hi = wilson(c, fed)
        line += f"{100 * c / fed:>8.1f} [{100 * lo:4.1f},{100 * hi:5.1f}] {100 - 100 * esc / fed:5.1f} {100 * (fed - c - esc) / fed:5.1f}"
    print(line)
print(f"{'wall s':<6}" + "".join(f"{rows[k + '/wall_s']:>30.1f}" for k in names))
PY
