#!/usr/bin/env bash
# MPI ranks against threads on this machine: 2 ranks × 1 thread against 1 rank × 2 threads
# (and 1 rank × 1 thread) on the scenes of `scg bench dilute|dense` and on
# cases/classifier.toml, with the shares of the step time of the decomposed runs.
#
#   bash bench/mpi.sh [--steps N] [--reps N] [--dilute N] [--dense N] [--classifier-s T] [--scg PATH]
#
#   --steps N         timed steps of the dilute cloud and the dense bed (default 200; + 5)
#   --reps N          runs per scene and configuration, alternating; the best counts (3)
#   --dilute N        particles of the dilute cloud (default 97336, as bench/vs-peers.sh)
#   --dense N         particles of the dense bed (default 32000, as bench/vs-peers.sh)
#   --classifier-s T  simulated time of the classifier, s (default 0.01: 50 000 steps)
#   --scg PATH        scg binary built with `--features mpi` (default target/release/scg,
#                     built with `cargo build --release --features mpi` if missing)
#   NICE="nice -n 5" prefixes every run alike (for a shared machine)
#   MPI_YIELD=0       busy-poll in MPI collectives (default: yield, see MPIRUN below)
#
# Configurations, each `scg run SCENE --no-record` (scene building excluded from the rate):
#   1x2        1 rank × 2 threads (the ordinary run)
#   1x1        1 rank × 1 thread
#   1x2 drv    1 rank × 2 threads through the decomposed driver (`mpirun -np 1` with
#              SCG_MPI_COUNTS=/dev/null): its migration share is the local per-step cost
#              of looking for leaving particles and digesting the ids, without any peer
#   2x1 slabs  `mpirun -np 2 scg run --threads 1` (slabs along the longest extent)
#   2x1 ids    the same with SCG_MPI_DECOMP=ids (particles shared by id: nothing migrates)
# Rate = particle-steps / wall time of the stepping loop (the `done:` line; summed over the
# ranks). Shares = the decomposed run's `share of the step time` line (compute, migration
# = the per-step collective, the exchange and the wait for the slower rank, recording,
# rebalance), of the best run.
#
# Particle contacts: a scene with `[contacts]` is refused on more than one rank until ghost
# particles are merged (branch `ghost`). Each scene is first tried with its contacts on 2
# ranks; when refused, the dense bed is skipped (it needs the ghost branch) and the dilute
# cloud and the classifier run WITHOUT particle contacts in every configuration (their
# `[contacts]` table removed; the classifier keeps its wall contacts). The lead reruns
# this after merging the ghost branch.
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
root=$PWD

STEPS=200
REPS=3
N_DILUTE=97336
N_DENSE=32000
CLASSIFIER_S=0.01
SCG=""
NICE=${NICE:-}
while [ $# -gt 0 ]; do
  case "$1" in
    --steps) STEPS=$2; shift ;;
    --reps) REPS=$2; shift ;;
    --dilute) N_DILUTE=$2; shift ;;
    --dense) N_DENSE=$2; shift ;;
    --classifier-s) CLASSIFIER_S=$2; shift ;;
    --scg) SCG=$2; shift ;;
    -h|--help) sed -n '2,36p' "$self"; exit 0 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
  shift
done

fail() { echo "FAIL: $*" >&2; exit 1; }
command -v mpirun >/dev/null || fail "mpirun not found (apt-get install openmpi-bin libopenmpi-dev)"
if [ -z "$SCG" ]; then
  SCG=$root/target/release/scg
  [ -x "$SCG" ] || cargo build --release --features mpi >&2
fi
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
# Unbound (a 1-rank run keeps both cores for its 2 threads) and yielding while waiting in
# a collective (busy polling steals the core the other rank needs on a loaded machine:
# 30-40 % slower here without it); MPI_YIELD=0 polls.
MPIRUN=(mpirun --oversubscribe --bind-to none --mca mpi_yield_when_idle "${MPI_YIELD:-1}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# The scenes: the benchmarks' own (`scg bench --scene-out`) and the case file.
"$SCG" bench dilute --particles "$N_DILUTE" --steps "$STEPS" --scene-out "$work/dilute.toml" 2>/dev/null ||
  fail "this scg has no \`bench --scene-out\`"
"$SCG" bench dense --particles "$N_DENSE" --steps "$STEPS" --scene-out "$work/dense.toml" 2>/dev/null
cp cases/classifier.toml "$work/classifier.toml"
drop_contacts() { # IN OUT: the scene without its [contacts] table
  python3 - "$1" "$2" <<'EOF'
import re, sys
text = open(sys.argv[1]).read()
out = re.sub(r'(^|\n)\[contacts\][^\n]*\n(?:[^\[\n][^\n]*\n|\n)*', r'\1', text)
assert out != text and '[contacts]' not in out, "no [contacts] table removed"
open(sys.argv[2], 'w').write(out)
EOF
}

# One run: CONFIG SCENE [--set ...]; prints "RATE COMPUTE MIGRATION RECORDING REBALANCE"
# (shares in %, "-" for the ordinary runs); exit 3 when contacts are refused.
run() {
  local cfg=$1 scene=$2
  shift 2
  local log=$work/log out
  case "$cfg" in
    1x2) $NICE "$SCG" run "$scene" --no-record --threads 2 "$@" >"$log" 2>&1 || true ;;
    1x1) $NICE "$SCG" run "$scene" --no-record --threads 1 "$@" >"$log" 2>&1 || true ;;
    1x2drv) SCG_MPI_COUNTS=/dev/null $NICE "${MPIRUN[@]}" -x SCG_MPI_COUNTS -np 1 "$SCG" run "$scene" \
      --no-record --threads 2 "$@" >"$log" 2>&1 || true ;;
    2x1slabs) $NICE "${MPIRUN[@]}" -np 2 "$SCG" run "$scene" --no-record --threads 1 "$@" >"$log" 2>&1 || true ;;
    2x1ids) SCG_MPI_DECOMP=ids $NICE "${MPIRUN[@]}" -x SCG_MPI_DECOMP -np 2 "$SCG" run "$scene" \
      --no-record --threads 1 "$@" >"$log" 2>&1 || true ;;
  esac
  if grep -q "particle contacts are not yet decomposed" "$log"; then
    return 3
  fi
  out=$(grep '^done:' "$log" | head -1) || { cat "$log" >&2; fail "$cfg $scene: no \`done:\` line"; }
  local rate
  rate=$(echo "$out" | sed -n 's/.*: \([0-9.e+-]*\) particle-steps\/s.*/\1/p')
  [ -n "$rate" ] || fail "$cfg: no rate in: $out"
  local share
  share=$(grep '^share of the step time' "$log" | sed -n \
    's/.*compute \([0-9.]*\) %, migration \([0-9.]*\) %, recording (gather) \([0-9.]*\) %, rebalance \([0-9.]*\) %.*/\1 \2 \3 \4/p')
  echo "$rate ${share:-- - - -}"
}

CONFIGS=(1x2 1x1 1x2drv 2x1slabs 2x1ids)
label() {
  case "$1" in
    1x2) echo "1 rank × 2 threads" ;;
    1x1) echo "1 rank × 1 thread" ;;
    1x2drv) echo "1 rank × 2 threads, MPI driver" ;;
    2x1slabs) echo "2 ranks × 1 thread, slabs" ;;
    2x1ids) echo "2 ranks × 1 thread, by id" ;;
  esac
}

# Best of REPS alternating runs of every configuration on SCENE (args after NAME SCENE
# go to `scg run`).
bench_scene() {
  local name=$1 scene=$2
  shift 2
  declare -A best=() shares=()
  local rep cfg line rate
  for rep in $(seq "$REPS"); do
    for cfg in "${CONFIGS[@]}"; do
      line=$(run "$cfg" "$scene" "$@") || fail "$name $cfg failed"
      rate=${line%% *}
      if [ -z "${best[$cfg]:-}" ] || python3 -c "import sys; sys.exit(not $rate > ${best[$cfg]})"; then
        best[$cfg]=$rate
        shares[$cfg]=${line#* }
      fi
    done
  done
  printf '%s\n' "$name (best of $REPS; particle-steps/s; shares of the step time in %: compute migration gather rebalance)"
  for cfg in "${CONFIGS[@]}"; do
    printf '  %-32s %10.3e   %s\n' "$(label "$cfg")" "${best[$cfg]}" "${shares[$cfg]}"
  done
  python3 -c "print(f'  ratio 2 ranks × 1 thread (best of slabs, ids) / 1 rank × 2 threads: {max(${best[2x1slabs]}, ${best[2x1ids]}) / ${best[1x2]}:.2f}')"
}

# Contacts on 2 ranks? (a short run of the dilute cloud)
contacts_ok=1
if ! run 2x1slabs "$work/dilute.toml" >/dev/null; then
  contacts_ok=0
fi
echo "scg: $SCG ($("$SCG" --version)); $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "mpirun: $(mpirun --version | head -1)"
echo
if [ "$contacts_ok" = 1 ]; then
  bench_scene "dilute cloud, $N_DILUTE particles, $STEPS + 5 steps (contacts on)" "$work/dilute.toml"
  echo
  bench_scene "dense bed, $N_DENSE particles, $STEPS + 5 steps (contacts on)" "$work/dense.toml"
  echo
  bench_scene "classifier, $CLASSIFIER_S s (contacts on)" "$work/classifier.toml" --set "duration=$CLASSIFIER_S"
else
  echo "NOTE: particle contacts are refused on 2 ranks (no ghost particles in this build):"
  echo "      the dense bed needs the ghost branch and is skipped; the dilute cloud and the"
  echo "      classifier run WITHOUT particle contacts ([contacts] removed) in every configuration."
  drop_contacts "$work/dilute.toml" "$work/dilute-nc.toml"
  drop_contacts "$work/classifier.toml" "$work/classifier-nc.toml"
  echo
  bench_scene "dilute cloud, $N_DILUTE particles, $STEPS + 5 steps (no particle contacts)" "$work/dilute-nc.toml"
  echo
  echo "dense bed, $N_DENSE particles: skipped (contacts refused on 2 ranks: needs the ghost branch)"
  echo
  bench_scene "classifier, $CLASSIFIER_S s (no particle contacts; wall contacts kept)" "$work/classifier-nc.toml" \
    --set "duration=$CLASSIFIER_S"
fi
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
