#!/usr/bin/env bash
# Run scg and LAMMPS (2 MPI ranks) on the same dense and dilute contact scenes and print
# particle-steps per second of each; the last two lines are the ratios scg/LAMMPS.
#
# Each code runs REPS times per scene, alternating with the other, and its best run
# counts: on a shared 2-core VM other tenants take whole milliseconds of CPU at random
# (steal time), and the best of several runs is the closest to a quiet machine for both.
#
#   bash bench/vs-lammps.sh                 # N_DILUTE=100000 N_DENSE=32000 STEPS=1000 REPS=3
#   N_DILUTE=260000 STEPS=2000 bash bench/vs-lammps.sh
set -euo pipefail
cd "$(dirname "$0")/.."

N_DILUTE=${N_DILUTE:-100000}
N_DENSE=${N_DENSE:-32000}
STEPS=${STEPS:-1000}
RANKS=${RANKS:-2}
REPS=${REPS:-3}

if ! command -v lmp >/dev/null; then
  echo "installing LAMMPS (Debian package lammps)…" >&2
  apt-get update >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y lammps >/dev/null
fi
cargo build --release --quiet
scg=target/release/scg

# particle-steps/s from LAMMPS's last "Loop time of T on P procs for S steps with N atoms".
lammps_rate() {
  awk '/^Loop time of/ {t=$4; s=$9; n=$12} END {if (t > 0) printf "%.4e\n", n*s/t; else print "nan"}'
}
scg_rate() { awk '/^particle-steps\/s:/ {print $2}'; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Dilute: SIDE³ particles on a jittered cubic lattice at solid fraction 0.01, d = 1 mm
# (the same construction as `scg bench dilute`).
SIDE=$(python3 -c "print(round(${N_DILUTE} ** (1/3)))")
N_DILUTE=$(( SIDE * SIDE * SIDE ))
read -r A J < <(python3 -c "import math; L=(${N_DILUTE}*math.pi/6*1e-9/0.01)**(1/3); a=L/${SIDE}; print(a, 0.45*(a-1e-3))")
# The largest of several numbers (one per line).
best() { sort -g | tail -1; }

lmp_dilute_runs=() scg_dilute_runs=() lmp_dense_runs=() scg_dense_runs=()
NZ=$(( (N_DENSE + 1599) / 1600 ))
for _ in $(seq "$REPS"); do
  lmp_dilute_runs+=("$(cd "$work" && mpirun --allow-run-as-root --oversubscribe -np "$RANKS" lmp -log none \
    -var SIDE "$SIDE" -var A "$A" -var J "$J" -var S "$STEPS" -in "$OLDPWD/bench/lammps/in.dilute" | lammps_rate)")
  scg_dilute_runs+=("$("$scg" bench dilute --particles "$N_DILUTE" --steps "$STEPS" | scg_rate)")
  lmp_dense_runs+=("$(cd "$work" && mpirun --allow-run-as-root --oversubscribe -np "$RANKS" lmp -log none \
    -var NZ "$NZ" -var S "$STEPS" -in "$OLDPWD/bench/lammps/in.dense" | lammps_rate)")
  scg_dense_runs+=("$("$scg" bench dense --particles $(( NZ * 1600 )) --steps "$STEPS" | scg_rate)")
done
echo "runs (particle-steps/s):"
echo "  dilute lammps: ${lmp_dilute_runs[*]}"
echo "  dilute scg:    ${scg_dilute_runs[*]}"
echo "  dense lammps:  ${lmp_dense_runs[*]}"
echo "  dense scg:     ${scg_dense_runs[*]}"
lmp_dilute=$(printf '%s\n' "${lmp_dilute_runs[@]}" | best)
scg_dilute=$(printf '%s\n' "${scg_dilute_runs[@]}" | best)
lmp_dense=$(printf '%s\n' "${lmp_dense_runs[@]}" | best)
scg_dense=$(printf '%s\n' "${scg_dense_runs[@]}" | best)

echo "dilute: N=$N_DILUTE steps=$STEPS  scg $scg_dilute  lammps $lmp_dilute particle-steps/s"
echo "dense:  N=$(( NZ * 1600 )) steps=$STEPS  scg $scg_dense  lammps $lmp_dense particle-steps/s"
python3 -c "print(f'dense ratio: {float(\"$scg_dense\")/float(\"$lmp_dense\"):.3f}')"
python3 -c "print(f'dilute ratio: {float(\"$scg_dilute\")/float(\"$lmp_dilute\"):.3f}')"
