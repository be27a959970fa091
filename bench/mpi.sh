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
#              SCG_MPI_DRIVER=1): what the driver itself costs, without any peer
#   2x1 slabs  `mpirun -np 2 scg run --threads 1` (slabs along the longest extent)
#   2x1 ids    the same with SCG_MPI_DECOMP=ids (particles shared by id: nothing migrates)
# Rate = particle-steps / wall time of the stepping loop (the `done:` line; summed over the
# ranks). Shares = the decomposed run's `share of the step time` line (compute, ghost
# exchange, migration = the per-step collective, the exchange and the wait for the slower
# rank, recording, rebalance), of the best run.
#
# Particle contacts run over ranks with ghost particles (slabs; in periodic boxes the slabs
# wrap round the box); shared by id they are refused, and that configuration is shown as
# refused. Each scene is first run with its contacts on 2 ranks in slabs; were that
# refused (the message is printed), the dense bed would be skipped and the dilute cloud
# and the classifier run WITHOUT particle contacts in every configuration.
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
    -h|--help) sed -n '2,37p' "$self"; exit 0 ;;
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
    1x2drv) SCG_MPI_DRIVER=1 $NICE "${MPIRUN[@]}" -x SCG_MPI_DRIVER -np 1 "$SCG" run "$scene" \
      --no-record --threads 2 "$@" >"$log" 2>&1 || true ;;
    2x1slabs) $NICE "${MPIRUN[@]}" -np 2 "$SCG" run "$scene" --no-record --threads 1 "$@" >"$log" 2>&1 || true ;;
    2x1ids) SCG_MPI_DECOMP=ids $NICE "${MPIRUN[@]}" -x SCG_MPI_DECOMP -np 2 "$SCG" run "$scene" \
      --no-record --threads 1 "$@" >"$log" 2>&1 || true ;;
  esac
  # Contacts refused on several ranks (exit 2 naming the contacts): the message, exit 3.
  if grep -m1 '^error: .*contacts' "$log" >"$work/refused"; then
    return 3
  fi
  out=$(grep '^done:' "$log" | head -1) || { cat "$log" >&2; fail "$cfg $scene: no \`done:\` line"; }
  case "$cfg" in
    1x2drv|2x1*) echo "$out" | grep -q " on [12] ranks:" ||
      fail "$cfg: not a decomposed run ($out): is $SCG built with --features mpi?" ;;
  esac
  local rate
  rate=$(echo "$out" | sed -n 's/.*: \([0-9.e+-]*\) particle-steps\/s.*/\1/p')
  [ -n "$rate" ] || fail "$cfg: no rate in: $out"
  local share
  share=$(grep '^share of the step time' "$log" | sed -n \
    's/.*compute \([0-9.]*\) %, ghost exchange \([0-9.]*\) %, migration \([0-9.]*\) %, recording (gather) \([0-9.]*\) %, rebalance \([0-9.]*\) %.*/\1 \2 \3 \4 \5/p')
  echo "$rate ${share:-- - - - -}"
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
# go to `scg run`); a configuration that refuses the scene's contacts is shown as such.
bench_scene() {
  local name=$1 scene=$2
  shift 2
  declare -A best=() shares=()
  local rep cfg line rate rc
  for rep in $(seq "$REPS"); do
    for cfg in "${CONFIGS[@]}"; do
      rc=0
      line=$(run "$cfg" "$scene" "$@") || rc=$?
      if [ "$rc" = 3 ]; then
        best[$cfg]=refused
        shares[$cfg]="refused: $(cat "$work/refused")"
        continue
      fi
      [ "$rc" = 0 ] || fail "$name $cfg failed"
      rate=${line%% *}
      if [ -z "${best[$cfg]:-}" ] || python3 -c "import sys; sys.exit(not $rate > ${best[$cfg]})"; then
        best[$cfg]=$rate
        shares[$cfg]=${line#* }
      fi
    done
  done
  printf '%s\n' "$name (best of $REPS; particle-steps/s; shares of the step time in %: compute ghosts migration gather rebalance)"
  for cfg in "${CONFIGS[@]}"; do
    if [ "${best[$cfg]}" = refused ]; then
      printf '  %-32s %10s   %s\n' "$(label "$cfg")" "-" "${shares[$cfg]}"
    else
      printf '  %-32s %10.3e   %s\n' "$(label "$cfg")" "${best[$cfg]}" "${shares[$cfg]}"
    fi
  done
  local two
  two=$(python3 -c "print(max([float(x) for x in ['${best[2x1slabs]}', '${best[2x1ids]}'] if x != 'refused'] or [0]))")
  python3 -c "print('  ratio 2 ranks × 1 thread (best of slabs, ids) / 1 rank × 2 threads: ' + (f'{$two / ${best[1x2]}:.2f}' if $two > 0 else 'none (refused)'))"
  python3 -c "print('  ratio 2 ranks × 1 thread (best of slabs, ids) / 1 rank × 1 thread: ' + (f'{$two / ${best[1x1]}:.2f}' if $two > 0 else 'none (refused)'))"
}

# A scene with particle contacts: as it is when 2 ranks in slabs take its contacts, else
# (refused) without them when NO_CONTACTS is given, else skipped.
# NAME SCENE NO_CONTACTS|"" [scg run args]
contact_scene() {
  local name=$1 scene=$2 nc=$3
  shift 3
  local rc=0
  run 2x1slabs "$scene" "$@" >/dev/null || rc=$?
  if [ "$rc" = 0 ]; then
    bench_scene "$name (contacts on)" "$scene" "$@"
  elif [ "$rc" = 3 ]; then
    local why
    why=$(cat "$work/refused")
    if [ -n "$nc" ]; then
      drop_contacts "$scene" "$nc"
      echo "NOTE: 2 ranks refuse its contacts ($why): WITHOUT particle contacts ([contacts] removed) in every configuration"
      bench_scene "$name (no particle contacts)" "$nc" "$@"
    else
      echo "$name: skipped, 2 ranks refuse its contacts ($why)"
      echo "  (a build without ghost particles refuses every scene with [contacts] on several ranks)"
    fi
  else
    fail "$name: the 2-rank probe failed"
  fi
}

echo "scg: $SCG ($("$SCG" --version)); $(nproc) cores, load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "mpirun: $(mpirun --version | head -1)"
echo
contact_scene "dilute cloud, $N_DILUTE particles, $STEPS + 5 steps" "$work/dilute.toml" "$work/dilute-nc.toml"
echo
contact_scene "dense bed, $N_DENSE particles, $STEPS + 5 steps" "$work/dense.toml" ""
echo
contact_scene "classifier, $CLASSIFIER_S s (wall contacts)" "$work/classifier.toml" "$work/classifier-nc.toml" \
  --set "duration=$CLASSIFIER_S"
echo
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
