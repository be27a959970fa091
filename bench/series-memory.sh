#!/usr/bin/env bash
# Memory and step rate of an unsteady series ([flow] series) against one frozen snapshot of
# it, on a large hexahedral box (scg's generator, crates/scg-mesh/examples/write_box_mesh.rs).
#
#   bash bench/series-memory.sh [--cells-per-side N] [--snapshots K] [--spacing S]
#                               [--particles P] [--threads T] [--scg PATH]
#
#   --cells-per-side N  N × N × N hexahedra over a 2 × 2 × 5 mm box (default 100: 10^6)
#   --snapshots K       time folders of the series (default 50)
#   --spacing S         their spacing, s (default 5e-4); dt = 1e-5 s
#   --particles P       particles, uniform in a cylinder (default 20000)
#   --threads T         scg's threads (default 1: the read-ahead thread has the other core)
#   KEEP=1 (environment) keeps the work folder and prints its path
#
# The field: the vortex about z whose rate swings in time (write_box_mesh --series), 20 µm
# particles of 2500 kg/m³, Schiller–Naumann drag, cell-point interpolation, walls rebound.
# Three runs over the whole window (K − 1 spacings), each under /usr/bin/time -v:
#   frozen  the first snapshot alone (`time = 0`)
#   pair    a series of the first two snapshots, cycling (two in memory, no read after
#           the start): what blending two snapshots costs
#   series  the K snapshots (each read ahead on a thread while the steps run)
# Prints each run's peak RSS and scg's done: line (steps' wall time, particle-steps/s),
# then the ratios series / frozen (memory) and series / pair (what the reads cost).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
N=100; K=50; SPACING=5e-4; P=20000; THREADS=1; SCG=""
while [ $# -gt 0 ]; do
  case "$1" in
    --cells-per-side) N=$2; shift ;;
    --snapshots) K=$2; shift ;;
    --spacing) SPACING=$2; shift ;;
    --particles) P=$2; shift ;;
    --threads) THREADS=$2; shift ;;
    --scg) SCG=$2; shift ;;
    -h|--help) sed -n '2,24p' "$self"; exit 0 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
  shift
done
if [ -z "$SCG" ]; then
  cargo build --release --bin scg -q
  SCG=target/release/scg
fi
cargo build --release -p scg-mesh --example write_box_mesh -q
work=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] && echo "work folder: $work" || trap 'rm -rf "$work"' EXIT
target/release/examples/write_box_mesh "$work/case" hex "$N" "$N" "$N" 1e-3 5e-3 --series "$K" "$SPACING"
span=$(python3 -c "print(($K - 1) * $SPACING)")
scene() { # $1: the flow's time selection line
  cat <<TOML
name = "series-memory"
duration = $span
dt = 1e-5
[fluid]
density = 1.2
viscosity = 1.8e-5
[drag]
law = "schiller_naumann"
[flow]
kind = "openfoam"
case = "case"
field = "U"
interpolation = "cell_point"
$1
[flow.patches]
wall_model = "rebound"
restitution = 1.0
walls = ["walls"]
outlets = ["inlet", "outlet"]
[[groups]]
name = "p"
diameter = 2e-5
density = 2500
count = $P
region = { kind = "cylinder", center = [0, 0, 0], axis = [0, 0, 1], radius_min = 0, radius_max = 9e-4, height = [2.5e-4, 4.75e-3] }
TOML
}
scene 'time = 0' > "$work/frozen.toml"
scene "series = { start = 0, end = $SPACING, cycle = true }" > "$work/pair.toml"
scene 'series = {}' > "$work/series.toml"
for run in frozen pair series; do
  (cd "$work" && /usr/bin/time -v "$OLDPWD/$SCG" --threads "$THREADS" run "$run.toml" --no-record \
    > "$run.out" 2> "$run.time")
  rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$work/$run.time")
  done_line=$(grep -h 'done:' "$work/$run.out" "$work/$run.time" | tail -1)
  echo "$run: peak RSS $((rss / 1024)) MB; $done_line"
  echo "$rss" > "$work/$run.rss"
done
python3 - "$work" <<'PY'
import re, sys, os
w = sys.argv[1]
def rss(r): return int(open(os.path.join(w, r + ".rss")).read())
def rate(r):
    for f in (r + ".out", r + ".time"):
        m = re.search(r"([0-9.e+]+) particle-steps/s", open(os.path.join(w, f)).read())
        if m: return float(m.group(1))
print("memory series / frozen: %.2f" % (rss("series") / rss("frozen")))
print("memory pair / frozen: %.2f" % (rss("pair") / rss("frozen")))
print("rate series / pair: %.3f" % (rate("series") / rate("pair")))
print("rate pair / frozen: %.3f" % (rate("pair") / rate("frozen")))
PY
