#!/usr/bin/env bash
# The cyclone's grade efficiency with and without what a RANS cyclone needs next to its
# walls: the wall function (the log law below the wall cells' centres) and turbulent
# dispersion (OpenFOAM's stochastic eddy model, or the drift-corrected Langevin walk),
# and the interpolation switch. Writes each variant of cases/cyclone.toml into --out,
# runs it for 6 s, prints η = 1 − escaped/fed per class with Wilson's 95 % interval.
#
#   bash cases/cyclone/near-wall.sh [--out DIR] [--feed-scale F] [--only NAMES]
#
# Variants: nowall (the no-slip ramp, no dispersion: the former scene), wall (the scene
# as committed), wall_eddy (+ stochastic_ras), wall_langevin (+ langevin),
# wall_langevin_cv (+ interpolation = cell_value), wall_langevin_mu (+ friction 0.3).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
out=/tmp/scg-cyclone-near-wall
feed=1
only=""
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --feed-scale) feed="$2"; shift 2 ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n 2,14p "$0"; exit 0 ;;
    *) echo "near-wall.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done
mkdir -p "$out"
scg="$root/target/release/scg"
[ -x "$scg" ] || (cd "$root" && cargo build --release --quiet)
python3 - "$root" "$out" <<'PY'
import sys
root, out = sys.argv[1], sys.argv[2]
src = open(f"{root}/cases/cyclone.toml").read()
src = src.replace('case = "cyclone/coarse"', f'case = "{root}/cases/cyclone/coarse"')
wall = '[flow.wall_function]\nmodel = "log_law"\nk = "kMean"\n'
assert wall in src, "cases/cyclone.toml has no [flow.wall_function]"
disp = lambda m: f'\n[dispersion]\nmodel = "{m}"\nk = "kMean"\nomega = "omegaMean"\n'
v = {
    "nowall": src.replace(wall, '[flow.wall_function]\nmodel = "none"\n'),
    "wall": src,
    "wall_eddy": src + disp("stochastic_ras"),
    "wall_langevin": src + disp("langevin"),
    "wall_langevin_cv": src.replace('field = "UMean"', 'field = "UMean"\ninterpolation = "cell_value"', 1) + disp("langevin"),
    "wall_langevin_mu": src.replace('wall_model = "rebound"', 'wall_model = "rebound"\nfriction = 0.3', 1) + disp("langevin"),
}
for k, s in v.items():
    open(f"{out}/{k}.toml", "w").write(s)
PY
names="nowall wall wall_eddy wall_langevin wall_langevin_cv wall_langevin_mu"
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
groups = [g for g, _, _ in rows[names[0]]]
print("eta = 1 - escaped/fed [95 % Wilson interval], 6 s, fed", rows[names[0]][0][1], "per class")
print(f"{'class':<6}" + "".join(f"{k:>24}" for k in names))
for i, g in enumerate(groups):
    line = f"{g:<6}"
    for k in names:
        _, fed, esc = rows[k][i]
        lo, hi = wilson(fed - esc, fed)
        line += f"{1 - esc / fed:>10.3f} [{lo:.3f},{hi:.3f}]"
    print(line)
print(f"{'wall s':<6}" + "".join(f"{rows[k + '/wall_s']:>24.1f}" for k in names))
PY
