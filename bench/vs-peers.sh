#!/usr/bin/env bash
# scg against its peers, LIGGGHTS 3.8 and LAMMPS (Debian packages), on the contact scenes of
# `scg bench dense|dilute`, with the same physics and both cores used by every code.
#
#   bash bench/vs-peers.sh [--large] [--steps N] [--reps N] [--check-steps N] [--scg PATH]
#
#   --large          dense bed of 128 000 particles instead of 32 000
#   --steps N        timed steps per run (default 1000; after 5 warm-up steps)
#   --reps N         runs per code, scene and rank count; the best counts (default 3)
#   --check-steps N  steps of the dense-bed physics check (default 2000)
#   --scg PATH       scg binary (default target/release/scg, built if missing)
#   NICE="nice -n 5" prefixes every run of every code alike (for a shared machine)
#
# 1. Installs lammps, liggghts and openmpi-bin with apt when a binary is missing.
# 2. Physics check (fails the script when a code disagrees with scg):
#    a two-sphere collision head-on (restitution within 1 %) and oblique (both velocity
#    components within 1 %), an oblique bounce on the floor (within 1 %), and the dense bed
#    after --check-steps steps (translational kinetic energy within 3 %, coordination
#    number and mean height within 1 %).
# 3. Timing: per repetition, for 2 and then 1 thread/rank, scg, LIGGGHTS and LAMMPS run one
#    after another on each scene (alternating); each code's best run of --reps counts.
#    Throughput = particles × timed steps / the code's own timer of the timed steps: scg's
#    `particle-steps/s` line (wall time of `sim.run` after 5 warm-up steps, scene building
#    excluded), the peers' `Loop time` of the second `run` command (after `run 5`; input
#    parsing, atom creation and the run's setup — first neighbour build, communication
#    set-up — excluded). Every peer run prints its MPI processor grid and atoms per rank;
#    a rank without atoms fails the script.
# The last lines are `dense ratio: X` and `dilute ratio: Y`: scg (2 threads) divided by the
# fastest peer with scg's physics (2 ranks), then the same against `lammps-fast`, LAMMPS's
# fastest granular style (pair gran/hertz/history: the same stiffness, its own damping).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
root=$PWD

N_DENSE=32000
N_DILUTE=97336
STEPS=1000
REPS=3
CHECK_STEPS=2000
SCG=""
NICE=${NICE:-}
while [ $# -gt 0 ]; do
  case "$1" in
    --large) N_DENSE=128000 ;;
    --steps) STEPS=$2; shift ;;
    --reps) REPS=$2; shift ;;
    --check-steps) CHECK_STEPS=$2; shift ;;
    --scg) SCG=$2; shift ;;
    -h|--help) sed -n '2,29p' "$self"; exit 0 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
  shift
done

fail() { echo "FAIL: $*" >&2; exit 1; }

# ---- 1. peers ------------------------------------------------------------------------------
if ! command -v lmp >/dev/null || ! command -v liggghts >/dev/null || ! command -v mpirun >/dev/null; then
  echo "installing lammps, liggghts, openmpi-bin (apt)…" >&2
  apt-get update >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
    lammps liggghts openmpi-bin >/dev/null
fi
LMP=$(command -v lmp) LIG=$(command -v liggghts) MPIRUN=$(command -v mpirun)
if [ -z "$SCG" ]; then
  SCG=target/release/scg
  [ -x "$SCG" ] || cargo build --release --quiet
fi
SCG=$(realpath "$SCG")
mpi_flags=()
[ "$(id -u)" = 0 ] && mpi_flags+=(--allow-run-as-root)
echo "scg:      $SCG"
echo "LIGGGHTS: $LIG ($(dpkg-query -W -f='${Version}' liggghts 2>/dev/null || echo '?'))"
echo "LAMMPS:   $LMP ($(dpkg-query -W -f='${Version}' lammps 2>/dev/null || echo '?'))"
echo "mpirun:   $MPIRUN ($("$MPIRUN" --version 2>/dev/null | head -1)) ${mpi_flags[*]}"
echo "cores: $(nproc)  load: $(cut -d' ' -f1-3 /proc/loadavg)  NICE='${NICE}'"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
py() { python3 "$root/bench/peers.py" "$@"; }

# The LAMMPS twin: pair granular hertz/material + damping tsuji + tangential mindlin is scg's
# model when its Tsuji polynomial α(e') is made to equal scg's exact γ(e) and the tangential
# dashpot is scaled to scg's (η_t/η_n = √(4G*/E*)). LAMMPS 29Sep2021's fix wall/gran
# hertz/material takes E* = E/(2(1−ν)) instead of E/(2(1−ν²)): E/(1+ν) corrects it; and its
# `tangential mindlin NULL` is not 8·G*, so the wall gets k_t = 8·G* explicitly.
read -r GAMMA EDAMP XGT ALPHA_E < <(py tsuji 0.9)
# LAMMPS's fastest granular style, as a LAMMPS user picks it for speed: pair
# gran/hertz/history with the same Hertz and Mindlin stiffness (4E*/3, 8G*) and its own
# damping m*·γn·v_n·√(R*δ), γn set for e = 0.9 head-on at 1 m/s (its restitution then
# grows as impacts slow: 0.94 at 0.1 m/s; γt = γn/2). Timed only, not in the physics check.
read -r KN KT GN < <(py hertz-history 0.9 1.0)
EWALL=$(python3 -c "print(repr(1e8/1.3))")
KTWALL=$(python3 -c "g = 1e8 / 2.6; print(repr(8 / (2 * 1.7 / g)))")
echo
echo "physics (all codes): d = 1 mm, ρ = 2500 kg/m³, E = 1e8 Pa, ν = 0.3, e = 0.9, μ = 0.5,"
echo "  dt = 1e-6 s, Hertz normal + Mindlin tangential spring with history + Coulomb limit,"
echo "  restitution damping γ(e) = √5·|ln e|/√(ln²e+π²) = $GAMMA (no rolling friction)"
echo "  LIGGGHTS: pair gran model hertz tangential history (its hertz damping is the same γ)"
echo "  LAMMPS:   pair granular hertz/material ... damping tsuji tangential mindlin NULL x μ:"
echo "            its Tsuji polynomial gives α(0.9) = $ALPHA_E ≠ γ, so it is handed e' = $EDAMP"
echo "            (α(e') = γ); x = √(4G*/E*) = $XGT (scg's tangential dashpot);"
echo "            floor: fix wall/gran with E = $EWALL (= E/(1+ν), see above) and"
echo "            tangential mindlin $KTWALL (= 8·G*) instead of NULL"
echo "  lammps-fast (timed only): pair gran/hertz/history kn = $KN (4E*/3), kt = $KT (8G*),"
echo "            γn = $GN (e = 0.9 at 1 m/s; velocity-dependent), γt = γn/2, dampflag 1;"
echo "            floor fix wall/gran hertz/history with the same constants"
echo "  neighbour lists (peers): neighbor 0.0001 bin (skin 0.1·d, as scg), neigh_modify delay 0"
echo "            every 1 check yes (rebuilt when an atom moved skin/2, as scg); newton off"
echo "            (LIGGGHTS's history pair needs it; the same for LAMMPS)"

# ---- runners ---------------------------------------------------------------------------------
# peer_run CODE NP INPUT VARS…: runs a peer in $work, output in $work/last.log.
peer_run() {
  local code=$1 np=$2 input=$3; shift 3
  local bin=$LMP; [ "$code" = liggghts ] && bin=$LIG
  (cd "$work" && $NICE "$MPIRUN" "${mpi_flags[@]}" -np "$np" "$bin" -log none "$@" -in "$input") \
    > "$work/last.log" 2>&1 || { tail -20 "$work/last.log" >&2; fail "$code run failed ($input)"; }
  grep -q '^ERROR' "$work/last.log" && { grep '^ERROR' "$work/last.log" >&2; fail "$code: error ($input)"; }
  return 0
}

# peer_rate NP: checks the last run's grid and atoms per rank, prints "RATE GRID NLOCAL".
peer_rate() {
  local np=$1 log=$work/last.log
  local grid loop nlocal
  grid=$(grep 'MPI processor grid' "$log" | tail -1 | awk '{print $1"x"$3"x"$5}')
  loop=$(grep '^Loop time of' "$log" | tail -1)
  nlocal=$(grep '^Nlocal:' "$log" | tail -1)
  [ -n "$grid" ] && [ -n "$loop" ] && [ -n "$nlocal" ] || fail "no grid/Loop/Nlocal line in the log"
  local procs t steps atoms
  read -r t procs steps atoms < <(echo "$loop" | awk '{print $4, $6, $9, $12}')
  [ "$procs" = "$np" ] || fail "ran on $procs procs, asked for $np"
  local ave max min
  read -r ave max min < <(echo "$nlocal" | awk '{print $2, $4, $6}')
  awk -v m="$min" 'BEGIN {exit !(m + 0 > 0)}' ||
    fail "a rank holds no atoms (grid $grid, Nlocal ave $ave max $max min $min): one core idles"
  local neighs builds
  neighs=$(grep '^Total # of neighbors' "$log" | tail -1 | awk '{print $NF}')
  builds=$(grep '^Neighbor list builds' "$log" | tail -1 | awk '{print $NF}')
  python3 -c "print(f'{$atoms * $steps / $t:.4e}', '$grid', 'atoms/rank min ${min%.*} max ${max%.*},', 'pairs listed ${neighs:-?}, list builds ${builds:-?}')"
}

scg_rate() { # NP SCENE N: prints "RATE THREADS"
  local out
  out=$($NICE "$SCG" --threads "$1" bench "$2" --particles "$3" --steps "$STEPS") || fail "scg bench $2 failed"
  local threads rate
  threads=$(echo "$out" | sed -n 's/.* on \([0-9]*\) threads.*/\1/p')
  rate=$(echo "$out" | awk '/^particle-steps\/s:/ {print $2}')
  [ "$threads" = "$1" ] || fail "scg ran on '$threads' threads, asked for $1"
  echo "$rate"
}

# Dense bed and dilute cloud parameters (as crates/scg-cli/src/bench.rs).
NZ=$(( (N_DENSE + 1599) / 1600 ))
N_DENSE=$(( NZ * 1600 ))
ZHI=$(( 4 * NZ + 10 ))
read -r SIDE A J < <(python3 -c "
import math
n = $N_DILUTE; side = round(n ** (1 / 3)); l = (n * math.pi / 6 * 1e-9 / 0.01) ** (1 / 3); a = l / side
print(side, repr(a), repr(0.45 * (a - 1e-3)))")
N_DILUTE=$(( SIDE * SIDE * SIDE ))
LMP_MODEL=(-var EDAMP "$EDAMP" -var XGT "$XGT" -var FAST 0 -var KN 0 -var KT 0 -var GN 0)
LMP_FAST=(-var EDAMP "$EDAMP" -var XGT "$XGT" -var FAST 1 -var KN "$KN" -var KT "$KT" -var GN "$GN")
dense_vars=(-var NZ "$NZ" -var ZHI "$ZHI" -var PZ 1)
dilute_vars=(-var SIDE "$SIDE" -var A "$A" -var J "$J")

# ---- 2. physics check ----------------------------------------------------------------------
echo
echo "== physics check"
within() { # NAME VALUE REFERENCE TOLERANCE(relative) [info]
  python3 - "$@" <<'EOF'
import sys
name, v, r, tol = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4])
bad = "differs" if len(sys.argv) > 5 else "FAIL"
rel = (v - r) / abs(r) if r != 0 else (0.0 if v == 0 else float("inf"))
ok = abs(rel) <= tol
print(f"  {name:<44} {v:.6e}  scg {r:.6e}  {100 * rel:+.3f} % (limit {100 * tol:g} %) {'ok' if ok else bad}")
sys.exit(0 if ok else 1)
EOF
}
check_fail=0
for vt in 0 0.25; do
  py collide-scene "$vt" > "$work/collide.toml"
  rm -rf "$work/fc"
  "$SCG" run "$work/collide.toml" --out "$work/rec" --frames-csv "$work/fc" > "$work/scg.log" 2>&1 ||
    { tail "$work/scg.log" >&2; fail "scg collision run failed"; }
  read -r s0x s0y s1x s1y < <(py collide "$work/fc/check-collide_000000200.csv")
  peer_run liggghts 1 "$root/bench/liggghts/in.collide" -var VT "$vt"
  read -r g0x g0y g1x g1y < <(grep '^COLLIDE' "$work/last.log" | awk '{print $2, $3, $4, $5}')
  peer_run lammps 1 "$root/bench/lammps/in.collide" -var VT "$vt" "${LMP_MODEL[@]}"
  read -r l0x l0y l1x l1y < <(grep '^COLLIDE' "$work/last.log" | awk '{print $2, $3, $4, $5}')
  if [ "$vt" = 0 ]; then
    echo " two spheres head-on at 1 m/s (restitution = separation / approach speed; set e = 0.9):"
    rs=$(python3 -c "print(($s1x) - ($s0x))")
    within "LIGGGHTS restitution" "$(python3 -c "print(($g1x) - ($g0x))")" "$rs" 0.01 || check_fail=1
    within "LAMMPS restitution (e' = ${EDAMP:0:8})" "$(python3 -c "print(($l1x) - ($l0x))")" "$rs" 0.01 || check_fail=1
    peer_run lammps 1 "$root/bench/lammps/in.collide" -var VT 0 -var EDAMP 0.9 -var XGT "$XGT"
    read -r a0x _ a1x _ < <(grep '^COLLIDE' "$work/last.log" | awk '{print $2, $3, $4, $5}')
    echo "  (LAMMPS handed e = 0.9 itself, its Tsuji polynomial: restitution $(python3 -c "print(f'{($a1x) - ($a0x):.6e}')"), not used)"
  else
    echo " oblique: ±(0.5, 0.25, 0) m/s, normal along x (sticking regime: the Mindlin spring decides):"
    within "LIGGGHTS vx' of sphere 0" "$g0x" "$s0x" 0.01 || check_fail=1
    within "LIGGGHTS vy' of sphere 0" "$g0y" "$s0y" 0.01 || check_fail=1
    within "LAMMPS vx' of sphere 0" "$l0x" "$s0x" 0.01 || check_fail=1
    within "LAMMPS vy' of sphere 0" "$l0y" "$s0y" 0.01 || check_fail=1
  fi
done

echo " oblique wall bounce: (0.5, 0, −1) m/s onto the floor z = 0 (the dense bed's floor):"
py wall-scene > "$work/wall.toml"
rm -rf "$work/fw"
"$SCG" run "$work/wall.toml" --out "$work/rec" --frames-csv "$work/fw" > "$work/scg.log" 2>&1 ||
  { tail "$work/scg.log" >&2; fail "scg wall run failed"; }
read -r swx swz swvz < <(py wall "$work/fw/check-wall_000000100.csv")
peer_run liggghts 1 "$root/bench/liggghts/in.wall"
read -r gwx gwz gwvz < <(grep '^WALL' "$work/last.log" | awk '{print $2, $3, $4}')
peer_run lammps 1 "$root/bench/lammps/in.wall" "${LMP_MODEL[@]}" -var EWALL "$EWALL" -var KTWALL "$KTWALL"
read -r lwx lwz lwvz < <(grep '^WALL' "$work/last.log" | awk '{print $2, $3, $4}')
within "LIGGGHTS vz' (normal restitution)" "$gwvz" "$swvz" 0.01 || check_fail=1
within "LIGGGHTS z after 100 steps" "$gwz" "$swz" 0.01 || check_fail=1
within "LIGGGHTS vx' (tangential)" "$gwx" "$swx" 0.01 || check_fail=1
within "LAMMPS vz' (normal restitution)" "$lwvz" "$swvz" 0.01 || check_fail=1
within "LAMMPS z after 100 steps (wall E* corrected)" "$lwz" "$swz" 0.01 || check_fail=1
within "LAMMPS vx' (tangential, k_t = 8·G* given)" "$lwx" "$swx" 0.01 || check_fail=1

echo " dense bed, $N_DENSE particles, $CHECK_STEPS steps from the packing at rest (2 threads/ranks):"
py dense-scene "$N_DENSE" "$CHECK_STEPS" > "$work/dense.toml"
rm -rf "$work/fd"
$NICE "$SCG" --threads 2 run "$work/dense.toml" --out "$work/rec" --frames-csv "$work/fd" > "$work/scg.log" 2>&1 ||
  { tail "$work/scg.log" >&2; fail "scg dense check run failed"; }
line=$(py state "$(ls "$work"/fd/check-dense_*.csv | sort | tail -1)")
read -r ske sz szm sn <<< "$line"
echo "  scg      KE $ske J, coordination $sz, mean z $szm m, $sn particles"
for code in liggghts lammps; do
  if [ "$code" = liggghts ]; then
    peer_run liggghts 2 "$root/bench/liggghts/in.dense" "${dense_vars[@]}" -var S 0 \
      -var CHECK "$CHECK_STEPS" -var DUMP "$work/$code.dump"
  else
    peer_run lammps 2 "$root/bench/lammps/in.dense" "${dense_vars[@]}" "${LMP_MODEL[@]}" \
      -var EWALL "$EWALL" -var KTWALL "$KTWALL" -var S 0 -var CHECK "$CHECK_STEPS" -var DUMP "$work/$code.dump"
  fi
  peer_rate 2 > /dev/null
  line=$(py state "$work/$code.dump")
  read -r ke z zm n <<< "$line"
  [ "$n" = "$sn" ] || fail "$code dumped $n particles, scg $sn"
  within "$code kinetic energy (J)" "$ke" "$ske" 0.03 || check_fail=1
  within "$code coordination number" "$z" "$sz" 0.01 || check_fail=1
  within "$code mean height (m)" "$zm" "$szm" 0.01 || check_fail=1
done
[ "$check_fail" = 0 ] || fail "physics check: a peer disagrees with scg (above)"
echo " physics check passed"

# ---- 3. timing -----------------------------------------------------------------------------
echo
echo "== timing: $STEPS timed steps, best of $REPS, order per repetition: dense then dilute,"
echo "   2 then 1 thread/rank, scg → LIGGGHTS → LAMMPS"
declare -A runs
for rep in $(seq "$REPS"); do
  for scene in dense dilute; do
    for np in 2 1; do
      if [ "$scene" = dense ]; then n=$N_DENSE; else n=$N_DILUTE; fi
      r=$(scg_rate "$np" "$scene" "$n")
      runs[scg,$scene,$np]+="$r "
      echo "  rep $rep $scene np=$np scg      $r particle-steps/s"
      for code in liggghts lammps lammps-fast; do
        if [ "$scene" = dense ]; then vars=("${dense_vars[@]}"); else vars=("${dilute_vars[@]}"); fi
        case "$code" in
          lammps) vars+=("${LMP_MODEL[@]}") ;;
          lammps-fast) vars+=("${LMP_FAST[@]}") ;;
        esac
        [ "$scene" = dense ] && [ "$code" != liggghts ] && vars+=(-var EWALL "$EWALL" -var KTWALL "$KTWALL")
        peer_run "$code" "$np" "$root/bench/${code%-fast}/in.$scene" "${vars[@]}" -var S "$STEPS" -var CHECK 0 -var DUMP none
        line=$(peer_rate "$np")  # in a command substitution, so that a FAIL stops the script
        read -r r grid rest <<< "$line"
        runs[$code,$scene,$np]+="$r "
        printf '  rep %s %s np=%s %-8s %s particle-steps/s  grid %s, %s\n' "$rep" "$scene" "$np" "$code" "$r" "$grid" "$rest"
      done
    done
  done
done

best() { tr ' ' '\n' | grep . | sort -g | tail -1; }
declare -A top
echo
echo "== best of $REPS (particle-steps/s; N dense = $N_DENSE, dilute = $N_DILUTE)"
printf '  %-7s %-11s %12s %12s %8s\n' scene code "1 thread" "2 threads" "2/1"
for scene in dense dilute; do
  for code in scg liggghts lammps lammps-fast; do
    b1=$(echo "${runs[$code,$scene,1]}" | best)
    b2=$(echo "${runs[$code,$scene,2]}" | best)
    top[$code,$scene]=$b2
    printf '  %-7s %-11s %12s %12s %8s\n' "$scene" "$code" "$b1" "$b2" "$(python3 -c "print(f'{$b2 / $b1:.2f}')")"
  done
done
echo "  (peers: threads = MPI ranks; neither Debian build has OpenMP styles)"
for scene in dense dilute; do
  python3 - "$scene" "${top[scg,$scene]}" "${top[liggghts,$scene]}" "${top[lammps,$scene]}" "${top[lammps-fast,$scene]}" <<'EOF'
import sys
scene, s, g, l, f = sys.argv[1], *map(float, sys.argv[2:])
peer, p = max(("liggghts", g), ("lammps", l), key=lambda t: t[1])
print(f"{scene}: scg {s:.4e} / fastest peer with the same physics {peer} {p:.4e}; "
      f"/ lammps-fast (gran/hertz/history, its own damping) {f:.4e} (2 threads/ranks)")
EOF
done
for scene in dense dilute; do
  python3 -c "print(f'$scene ratio: {${top[scg,$scene]} / max(${top[liggghts,$scene]}, ${top[lammps,$scene]}):.3f}')"
done
for scene in dense dilute; do
  python3 -c "print(f'$scene ratio to lammps-fast: {${top[scg,$scene]} / ${top[lammps-fast,$scene]}:.3f}')"
done
