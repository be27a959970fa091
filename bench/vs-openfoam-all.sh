#!/usr/bin/env bash
# scg against OpenFOAM's own particle tracker on every shipped side by side, one table:
# each case's own script runs both codes with the same models, particles and dt (see each
# script's header), and this one collects their speeds and whether their answers agree.
#
#   bash bench/vs-openfoam-all.sh [--cases "hex tet elbow squarebend duct"] [--reps N]
#                                 [--out DIR]
#
#   --cases LIST  any of: hex, tet (bench/vs-openfoam.sh [--mesh tet]: the vortex box,
#                 Schiller–Naumann, elastic walls), elbow (cases/elbow/vs-openfoam.sh:
#                 dispersion, rebound, erosion), squarebend (cases/squarebend/vs-openfoam.sh:
#                 sticking walls), duct (cases/cyclone/vs-openfoam.sh --scene cases/duct.toml:
#                 stochasticDispersionRAS), cyclone (cases/cyclone/vs-openfoam.sh: the
#                 cyclone's like-for-like scene; about 10 minutes); default all but cyclone
#   --reps N      repetitions of the hex and tet timing (best of N; default 2)
#   --out DIR     each case's log and the table (default /tmp/scg-vs-openfoam-all)
#
# Columns: OpenFOAM v1912 on one process, particle-steps per CPU second (its ExecutionTime);
# scg on one thread (the vortex boxes: wall time of one thread; the CFD cases: the CPU time
# of the steps on two threads, from `scg run`'s `done:` line, so the ratio is per core);
# per core = scg / OpenFOAM, CPU time against CPU time; answers: the case's own agreement
# check (the vortex boxes: positions and velocities per particle within the script's
# limits; the CFD cases: every fate's 95 % interval overlapping the other code's, or the
# largest difference in standard deviations). Prints the table and writes DIR/table.md.
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
CASES="hex tet elbow squarebend duct"
REPS=2
OUT=/tmp/scg-vs-openfoam-all
while [ $# -gt 0 ]; do
  case "$1" in
    --cases) CASES=$2; shift ;;
    --reps) REPS=$2; shift ;;
    --out) OUT=$2; shift ;;
    -h|--help) sed -n '2,24p' "$self"; exit 0 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
  shift
done
mkdir -p "$OUT"
cargo build --release --bin scg -q
rows=()
# the CPU seconds of OpenFOAM's steps and of scg's, from a case script's log ("X s CPU
# (ExecutionTime)" and scg's "done: … (CPU C s)")
cpu_pair() {
  local of scg
  of=$(grep -oE '[0-9.]+ s CPU \(ExecutionTime\)' "$1" | head -1 | awk '{print $1}')
  scg=$(grep -oE '\(CPU [0-9.]+ s\)' "$1" | head -1 | tr -d '()' | awk '{print $2}')
  echo "$of $scg"
}
for c in $CASES; do
  log="$OUT/$c.log"
  echo "== $c (log: $log)" >&2
  case "$c" in
    hex|tet)
      # the script fails when the codes' particles disagree beyond its limits
      if bash bench/vs-openfoam.sh --mesh "$c" --reps "$REPS" > "$log" 2>&1; then
        ok="yes (per particle)"
      else
        ok="no (see log)"
      fi
      of=$(awk -F': ' '/^openfoam particle-steps\/s:/ {print $2}' "$log")
      one=$(awk -F': ' '/^scg 1 thread:/ {print $2}' "$log")
      two=$(awk -F': ' '/^scg 2 threads:/ {print $2}' "$log")
      cpu=$(grep -oE 'CPU time [0-9.]+' "$log" | awk '{print $3}')
      cells=$([ "$c" = hex ] && echo "160 000 hexahedra" || echo "160 800 tetrahedra")
      rows+=("| vortex box, $cells, 10^5 particles | $of | $one | $cpu× | $two | $ok |")
      ;;
    elbow|squarebend)
      bash "cases/$c/vs-openfoam.sh" > "$log" 2>&1 || true
      read -r ofc scgc < <(cpu_pair "$log")
      ratio=$(python3 -c "print('%.2f' % ($ofc / $scgc))")
      ofc=$(printf '%.2f' "$ofc")
      ok=$(grep -q 'all intervals overlap: yes' "$log" && echo "yes (every fate's interval)" || echo "no (see log)")
      rows+=("| $c | $ofc s | $scgc s (2 threads) | $ratio× | — | $ok |")
      ;;
    duct|cyclone)
      args=(--out "$OUT/$c")
      [ "$c" = duct ] && args+=(--scene cases/duct.toml --split "1 2 1")
      bash cases/cyclone/vs-openfoam.sh "${args[@]}" > "$log" 2>&1 || true
      rate() { grep -E "$1" "$log" | head -1 | sed -E 's/^[^:]*: +([0-9.e+]+).*/\1/'; }
      of=$(rate 'OpenFOAM, 1 process:')
      one=$(rate 'scg, 1 thread *:')
      two=$(rate 'scg, 2 threads:')
      ratio=$(grep -oE 'per core \(scg 1 thread / OpenFOAM 1 process, CPU\): [0-9.]+' "$log" | awk '{print $NF}')
      worst=$(awk '/^ *[a-z0-9]+ +[0-9]+ \|/ && NF > 10 {d = $(NF-1); s = $NF; if (d < 0) d = -d; if (s > 0 && d / s > m) m = d / s} END {printf "%.2f", m}' "$log")
      rows+=("| $c | $of | $one | $ratio× | $two | largest difference ${worst} σ |")
      ;;
    *) echo "unknown case: $c" >&2; exit 2 ;;
  esac
done
{
  echo "| case | OpenFOAM, 1 process, per CPU s | scg, 1 thread | per core | scg, 2 threads | answers agree |"
  echo "|---|---|---|---|---|---|"
  printf '%s\n' "${rows[@]}"
  echo
  echo "Elbow and squareBend: CPU seconds of the whole run's steps (OpenFOAM's ExecutionTime; scg's \`done:\` line on two threads); the others particle-steps per second. $(date -u +%F), $(nproc) cores, $(lscpu | awk -F': *' '/Model name/ {print $2; exit}')."
} | tee "$OUT/table.md"
