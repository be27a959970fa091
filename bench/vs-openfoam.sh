#!/usr/bin/env bash
# scg's mesh-flow tracker against OpenFOAM's own (Debian package openfoam, v1912,
# icoUncoupledKinematicParcelFoam: kinematic parcels through a frozen U) on the same mesh,
# field, particles, drag, interpolation and dt. OpenFOAM runs on one process.
#
#   bash bench/vs-openfoam.sh [--mesh hex|tet] [--particles N] [--steps N] [--reps N]
#                             [--check-steps N] [--check-particles N] [--scg PATH]
#
#   --mesh hex|tet       40 × 40 × 100 = 160 000 hexahedra by blockMesh (default), or
#                        20 × 20 × 67 hexahedra split into 6 tetrahedra each = 160 800
#                        tetrahedra, interior points perturbed by up to 0.2 spacings (scg's
#                        generator, crates/scg-mesh/examples/write_box_mesh.rs, built if
#                        missing)
#   --particles N        particles of the timed runs (default 100000)
#   --steps N            steps per timed run (default 60; OpenFOAM's first 2 are excluded)
#   --reps N             runs per code and thread count; the best counts (default 3)
#   --check-steps N      steps of the physics check (default 1000)
#   --check-particles N  particles of the physics check (default 10000)
#   --scg PATH           scg binary (default target/release/scg, built if missing)
#   KEEP=1 (environment) keeps the work folder (cases, logs) and prints its path
#   NICE="nice -n 5" prefixes every run of every code alike (for a shared machine)
#
# The case (bench/foam.py, templates in bench/openfoam/): a 2 × 2 × 5 mm box holding the
# paper's vortex about z (ω = 31.4 rad/s, k = 0.1) plus an axial flow
# u_z = 0.01·(1 − r²/R²) m/s sampled at the cell centres (OpenFOAM's writeCellCentres),
# frozen; the sides a wall patch (elastic rebound), top and bottom patches `outlet` and
# `inlet` (particles leave); particles d = 20 µm, ρ = 2500 kg/m³, uniformly at random in a
# cylinder, sorted by cell, starting at (0.1, 0, 0.2) m/s (some rebound from the wall
# x = W, some leave through the outlet); no gravity; dt = 1e-5 s.
#
# 1. Installs openfoam with apt when icoUncoupledKinematicParcelFoam is missing.
# 2. Physics check (fails the script when the codes disagree): --check-particles particles,
#    --check-steps steps; positions and velocities per particle (OpenFOAM's origId = scg's
#    id), the counts still in the box, mean x and z, against limits (bench/foam.py
#    compare), and against the scale of what the drag correlation alone does: scg once
#    more with Stokes drag.
# 3. Timing: per repetition OpenFOAM (1 process), scg 1 thread, scg 2 threads, one after
#    another; the best of --reps counts. OpenFOAM: its own ExecutionTime (CPU time,
#    printed after every step) of the steps after the first two (start-up, injection and
#    the first location excluded), and the wall time of the same lines (timestamped as
#    the log is written). scg: its `done: ... particle-steps/s` line (wall time of the
#    run's steps, the first step's location of every particle included; scene loading
#    excluded) and, on one thread, its CPU time of the same steps (the line's `(CPU … s)`,
#    the process's user + system time over them, 10 ms resolution).
# After the table, the ratios with one timer for both (wall: scg 2 threads / OpenFOAM;
# CPU: scg 1 thread / OpenFOAM); the last lines are `openfoam particle-steps/s: X`
# (ExecutionTime), `scg 1 thread: Y`, `scg 2 threads: Z` (their own lines) and
# `ratio (scg 2 threads / openfoam 1 process): R` = Z / X (CPU time against wall time:
# meaningful only on a quiet machine, where OpenFOAM's CPU time is its wall time).
set -euo pipefail
self=$(realpath "$0")
cd "$(dirname "$self")/.."
root=$PWD

MESH=hex
N=100000
STEPS=60
REPS=3
CHECK_STEPS=1000
CHECK_N=10000
SCG=""
NICE=${NICE:-}
while [ $# -gt 0 ]; do
  case "$1" in
    --mesh) MESH=$2; shift ;;
    --particles) N=$2; shift ;;
    --steps) STEPS=$2; shift ;;
    --reps) REPS=$2; shift ;;
    --check-steps) CHECK_STEPS=$2; shift ;;
    --check-particles) CHECK_N=$2; shift ;;
    --scg) SCG=$2; shift ;;
    -h|--help) sed -n '2,48p' "$self"; exit 0 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
  shift
done
[ "$STEPS" -ge 5 ] || { echo "--steps must be at least 5" >&2; exit 2; }
case "$MESH" in hex) CELLS=160000 ;; tet) CELLS=160800 ;; *) echo "--mesh hex|tet" >&2; exit 2 ;; esac
SKIP=2

fail() { echo "FAIL: $*" >&2; exit 1; }

# ---- 1. OpenFOAM ---------------------------------------------------------------------------
if ! command -v icoUncoupledKinematicParcelFoam >/dev/null || ! command -v blockMesh >/dev/null; then
  echo "installing openfoam (apt)…" >&2
  apt-get update >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends openfoam >/dev/null
fi
# The environment (FOAM_*, WM_*): its bashrc reads unset variables and calls helpers the
# Debian package lacks, hence no `set -u` and no output around it.
set +u
# shellcheck disable=SC1091
source /usr/share/openfoam/etc/bashrc >/dev/null 2>&1 || true
set -u
FOAM=$(command -v icoUncoupledKinematicParcelFoam)
if [ -z "$SCG" ]; then
  SCG=target/release/scg
  [ -x "$SCG" ] || cargo build --release --quiet
fi
SCG=$(realpath "$SCG")
BOXMESH=$root/target/release/examples/write_box_mesh
if [ "$MESH" = tet ] && [ ! -x "$BOXMESH" ]; then
  cargo build --release --quiet -p scg-mesh --example write_box_mesh
fi
echo "scg:      $SCG"
echo "OpenFOAM: $FOAM ($(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'), WM_PROJECT_VERSION=${WM_PROJECT_VERSION:-?})"
echo "cores: $(nproc)  load: $(cut -d' ' -f1-3 /proc/loadavg)  NICE='${NICE}'"

work=$(mktemp -d)
[ -n "${KEEP:-}" ] && echo "work: $work (kept)" || trap 'rm -rf "$work"' EXIT
py() { python3 "$root/bench/foam.py" "$@"; }

# scg's name for OpenFOAM's cellPoint (inverse-distance point values): `cell_point_idw`
# where scg has it, else `cell_point`. (The binary names its schemes in its validation
# messages; a probe scene would need a mesh, which blockMesh makes only later.)
INTERP=cell_point
if grep -aq cell_point_idw "$SCG"; then
  INTERP=cell_point_idw
fi

echo
echo "case (both codes), mesh: $MESH, $CELLS cells"
py params | sed 's/^/  /'
echo "  OpenFOAM: $(basename "$FOAM"), one process; U read once from 0/U, never solved (no"
echo "            flow equation; laminar turbulence model object only); manualInjection of"
echo "            one particle per parcel at t = 0 from constant/kinematicCloudPositions, U0 as scg;"
echo "            sphereDrag (Cd = 24/Re·(1 + Re^(2/3)/6)); interpolation U cellPoint, rho and"
echo "            mu cell; integrationSchemes U analytical; maxCo 1 (track to every face);"
echo "            standardWallInteraction rebound e = 1, mu = 0 on the wall patch, escape"
echo "            through the patches outlet and inlet; collisionModel, dispersionModel none;"
echo "            coupled false"
echo "  scg:      [flow] kind = \"openfoam\" on the same case folder, interpolation = \"$INTERP\";"
echo "            [drag] law = \"schiller_naumann\" (Cd = 24/Re·(1 + 0.15·Re^0.687)); the"
echo "            exponential integrator; flow.patches walls = [\"walls\"] (specular, e = 1),"
echo "            outlets = [\"outlet\"] (inlet: lost); the same positions and initial velocity in [[groups]]"

# foam_case DIR N STEPS: an OpenFOAM case with its mesh and field, and scg's scene in it.
foam_case() {
  if [ "$MESH" = tet ]; then
    "$BOXMESH" "$1" tet 20 20 67 0.001 0.005 0.2 > /dev/null || fail "write_box_mesh"
  fi
  py case "$1" "$2" "$3" 7 "$INTERP"
  if [ "$MESH" = hex ]; then
    (cd "$1" && blockMesh > log.blockMesh 2>&1) || { tail "$1/log.blockMesh" >&2; fail "blockMesh"; }
  fi
  mkdir -p "$1/0"
  (cd "$1" && postProcess -func writeCellCentres -time 0 > log.cc 2>&1) ||
    { tail "$1/log.cc" >&2; fail "postProcess -func writeCellCentres"; }
  local n
  n=$(py field "$1")
  [ "$n" = "$CELLS" ] || fail "the $MESH mesh has $n cells, not $CELLS"
}

# ---- 2. physics check ----------------------------------------------------------------------
echo
echo "== physics check: $CHECK_N particles, $CHECK_STEPS steps"
chk=$work/check
foam_case "$chk" "$CHECK_N" "$CHECK_STEPS"
(cd "$chk" && py run log.foam "$FOAM" > /dev/null) || { tail -30 "$chk/log.foam" >&2; fail "OpenFOAM check run failed"; }
grep -q "FOAM FATAL" "$chk/log.foam" && { grep -A5 "FOAM FATAL" "$chk/log.foam" >&2; fail "OpenFOAM error"; }
ftime=$(cd "$chk" && ls -d [0-9]* | grep -v '^0$' | sort -g | tail -1)
echo "  OpenFOAM wrote time $ftime; parcels: $(grep 'Current number of parcels' "$chk/log.foam" | tail -1 | awk '{print $NF}')"
"$SCG" run "$chk/scene.toml" --out "$work/rec" --frames-csv "$work/fc" > "$work/scg-check.log" 2>&1 ||
  { tail "$work/scg-check.log" >&2; fail "scg check run failed"; }
csv=$(ls "$work"/fc/vs-openfoam_*.csv | sort | tail -1)
"$SCG" run "$chk/scene.toml" --set drag.law=stokes --out "$work/rec" --frames-csv "$work/fs" > "$work/scg-check.log" 2>&1 ||
  { tail "$work/scg-check.log" >&2; fail "scg check run (Stokes) failed"; }
csv_stokes=$(ls "$work"/fs/vs-openfoam*_*.csv | sort | tail -1)   # named vs-openfoam-drag.law=stokes_<step>
want=CellPoint
[ "$INTERP" = cell_point_idw ] && want=CellPointIdw
grep -q "field \`U\` ($want)" <("$SCG" check "$chk/scene.toml" 2>&1) || fail "scg is not on $INTERP"
echo "  scg: $(basename "$csv") ($(( CHECK_STEPS + 1 )) steps: OpenFOAM's first step updates the new parcels' velocity twice)"
py compare "$chk" "$ftime" "$csv" "$CHECK_N" "$csv_stokes" || fail "physics check: the codes disagree (above)"
rm -rf "$chk" "$work/fc" "$work/fs" "$work/rec"

# ---- 3. timing -----------------------------------------------------------------------------
echo
echo "== timing: $N particles, $STEPS steps per run, best of $REPS; per repetition OpenFOAM,"
echo "   scg 1 thread, scg 2 threads"
tc=$work/time
foam_case "$tc" "$N" "$STEPS"
py steps "$tc" "$STEPS"   # no write time in the run
# one short scg run first (the case read once, files in the page cache for every timed run)
py run "$work/scg0.log" $NICE "$SCG" --threads 1 run "$tc/scene.toml" --no-record \
  --set duration=1e-5 > /dev/null || { tail "$work/scg0.log" >&2; fail "scg start-up run failed"; }
declare -A runs
for rep in $(seq "$REPS"); do
  (cd "$tc" && rm -rf [1-9]* 0.[0-9]* && py run log.foam $NICE "$FOAM" > /dev/null) ||
    { tail -30 "$tc/log.foam" >&2; fail "OpenFOAM run failed"; }
  n_end=$(grep 'Current number of parcels' "$tc/log.foam" | tail -1 | awk '{print $NF}')
  [ "$n_end" -ge $(( N * 99 / 100 )) ] || fail "OpenFOAM lost particles: $n_end of $N"
  read -r fc fw fsteps < <(py rate "$tc/log.foam" "$N" "$SKIP")
  runs[foam]+="$fc "; runs[foamwall]+="$fw "
  echo "  rep $rep OpenFOAM  $fc particle-steps/s (ExecutionTime, $fsteps steps), wall $fw"
  for t in 1 2; do
    py run "$work/scg.log" $NICE "$SCG" --threads "$t" run "$tc/scene.toml" --no-record \
      --set duration="$(python3 -c "print($STEPS * 1e-5)")" > /dev/null ||
      { tail "$work/scg.log" >&2; fail "scg run failed"; }
    line=$(grep '^done:' "$work/scg.log") || fail "no done: line from scg"
    r=$(echo "$line" | sed -n 's/.*: \([0-9.e+-]*\) particle-steps\/s.*/\1/p')
    steps=$(echo "$line" | awk '{print $2}')
    [ "$steps" = "$STEPS" ] || fail "scg ran $steps steps"
    runs[scg$t]+="$r "
    if [ "$t" = 1 ]; then
      # its CPU time of the same steps: r × wall / CPU from the done: line
      read -r wall cpus < <(echo "$line" | sed -n 's/.* in \([0-9.]*\) s (CPU \([0-9.]*\) s).*/\1 \2/p') ||
        fail "no CPU time on scg's done: line"
      rc=$(python3 -c "print(f'{$r * $wall / $cpus:.4e}')")
      runs[scgcpu]+="$rc "
      echo "  rep $rep scg 1     $r particle-steps/s (own line), CPU $rc"
    else
      echo "  rep $rep scg 2     $r particle-steps/s (own line)"
    fi
  done
done

best() { tr ' ' '\n' | grep . | sort -g | tail -1; }
F=$(echo "${runs[foam]}" | best); FW=$(echo "${runs[foamwall]}" | best)
S1=$(echo "${runs[scg1]}" | best); S2=$(echo "${runs[scg2]}" | best)
SC=$(echo "${runs[scgcpu]}" | best)
echo
echo "== best of $REPS (particle-steps/s; $N particles, $CELLS cells ($MESH); load now $(cut -d' ' -f1-3 /proc/loadavg))"
printf '  %-26s %14s %14s\n' code "own timer" "other timer"
printf '  %-26s %14s %14s\n' "OpenFOAM, 1 process" "$F" "$FW"
printf '  %-26s %14s %14s\n' "scg, 1 thread" "$S1" "$SC"
printf '  %-26s %14s %14s\n' "scg, 2 threads" "$S2" "-"
echo "  (own timer: OpenFOAM's ExecutionTime = CPU time, scg's wall time; other timer:"
echo "   OpenFOAM's wall time of the same steps, scg's CPU time on one thread)"
python3 -c "print(f'same timer for both: wall time {$S2 / $FW:.3f} (scg 2 threads / OpenFOAM 1 process), CPU time {$SC / $F:.3f} (scg 1 thread / OpenFOAM)')"
echo "openfoam particle-steps/s: $F"
echo "scg 1 thread: $S1"
echo "scg 2 threads: $S2"
python3 -c "print(f'ratio (scg 2 threads / openfoam 1 process): {$S2 / $F:.3f}')"
