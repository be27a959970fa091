#!/usr/bin/env bash
# The cyclone side by side with OpenFOAM's particle tracker: the scene's frozen field,
# inlet-patch feed, sizes, densities, drag and wall rebound in uncoupledKinematicParcelFoam
# (Debian's OpenFOAM v1912, one process) and in scg (original particles, 1 and 2 threads);
# one table of grade efficiency, counts and speed.
#
#   bash cases/cyclone/vs-openfoam.sh [--scene cases/cyclone.toml] [--quick] [--out DIR]
#                                     [--scg PATH] [--openfoam-only] [--split "A B C"]
#
#   --scene FILE  the scg scene (default cases/cyclone.toml; what OpenFOAM's tracker has no
#                 model for — scg's [flow.wall_function], [[zones]] that collect — is
#                 switched off in both, written to OUT/scene.toml): [flow] kind = "openfoam" with
#                 a fixed dt, one [[feeders]] with `patch` per [[groups]] size class,
#                 [flow.patches] walls (wall_model "rebound", [material] restitution),
#                 outlets, inlets; [drag], [gravity], [fluid]; [dispersion] model =
#                 "stochastic_ras" with k = FIELD and omega = FIELD (or epsilon = FIELD),
#                 fields of the flow's time folder: OpenFOAM's stochasticDispersionRAS on a
#                 frozen RAS model (kOmegaSST, epsilon = 0.09 k omega; kEpsilon) whose k and
#                 omega are those files (kMean, omegaMean: the same fields as scg's)
#   --quick       a check of the script (seconds): duration 0.4 s and a quarter of the
#                 feed rates (--set duration=0.4 --set feed_scale=0.25 for scg)
#   --out DIR     results (default /tmp/scg-cyclone-vs-openfoam): grade.json (OpenFOAM,
#                 the shape `scg study cyclone --openfoam FILE` reads), scg-1.json and
#                 scg-2.json (`scg run --summary-json`), table.txt, openfoam/ (the cases
#                 and their logs)
#   --feed-scale F  multiply every feeder's rate by F in both codes (scg's feed_scale;
#                 more particles, a smaller sampling error: the table prints it)
#   --split "A B C"  the 2-rank decomposition (default "2 1 1"; the duct: "1 2 1")
#   --dt DT       the time step of both codes instead of the scene's (scg: --set dt=DT)
#   --scg-set KEY=VALUE  passed to both scg runs as --set (repeatable), e.g.
#                 flow.interpolation=cell_point_idw (OpenFOAM's cellPoint point values);
#                 for scg only: keys that change the physics break the like-for-like
#   --scg PATH    scg binary (default target/release/scg, built if missing)
#   --openfoam-only  OpenFOAM's runs alone (1 process, 2 ranks, two at once): grade.json
#                 and a summary (summary.txt), no scg run and no table
#   NICE="nice -n 5" prefixes every run of both codes alike (for a shared machine)
#
# Steps: installs OpenFOAM with apt when missing (as cases/cyclone/build.sh); writes one
# OpenFOAM case per particle density (cases/cyclone/vs_openfoam.py case: one kinematic
# cloud has a single rho0); runs uncoupledKinematicParcelFoam (bench/foam.py run: its log,
# and the wall time of every ExecutionTime line), then the same case decomposed in two
# (decomposePar, simple (2 1 1); mpirun -np 2 ... -parallel, failing when a processor holds
# no parcel), and two serial copies at once (one per core); reads the fed, escaped (outlet patches),
# lost (other non-wall patches) and held parcels per class (the injectors' `parcels added`,
# patchPostProcessing, the parcels written at the end) into grade.json; runs scg on the
# same scene twice (--threads 1 and 2, --no-record, --summary-json); prints the table
# (cases/cyclone/vs_openfoam.py table). Timers: OpenFOAM's ExecutionTime (CPU time of the
# process) over steps 2..N; scg's wall time of its steps (scene and mesh loading
# excluded). particle-steps: the sum over steps of the particles in the domain, both codes.
set -eo pipefail
self=$(realpath "$0")
root=$(cd "$(dirname "$self")/../.." && pwd)
scene=$root/cases/cyclone.toml
out=/tmp/scg-cyclone-vs-openfoam
quick=0
dt=""
case_args=()
set_args=()
feed_scale=""
scg_set=()
SCG=""
foam_only=0
split="2 1 1"
NICE=${NICE:-}
while [ $# -gt 0 ]; do
    case "$1" in
        --scene) scene=$2; shift ;;
        --out) out=$2; shift ;;
        --quick) quick=1 ;;
        --scg) SCG=$2; shift ;;
        --openfoam-only) foam_only=1 ;;
        --feed-scale) feed_scale=$2; shift ;;
        --split) split=$2; shift ;;
        --dt) case_args+=(--dt "$2"); set_args+=(--set "dt=$2"); dt=$2; shift ;;
        --scg-set) scg_set+=(--set "$2"); shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$self"; exit 0 ;;
        *) echo "vs-openfoam.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
[ -f "$scene" ] || { echo "vs-openfoam.sh: no scene $scene" >&2; exit 2; }
scene=$(realpath "$scene")
mkdir -p "$out"
out=$(realpath "$out")
# The scene as both codes run it: what OpenFOAM's tracker has no model for (scg's wall
# function, a collecting zone) is switched off in scg too (vs_openfoam.py like).
python3 "$root/cases/cyclone/vs_openfoam.py" like "$scene" "$out/scene.toml" | sed 's/^/like for like: /'
echo "scene as run by both: $out/scene.toml (from $scene)"
scene=$out/scene.toml

# --- OpenFOAM (as cases/cyclone/build.sh) ---------------------------------------------------
# shellcheck source=../foam-env.sh
source "$(dirname "$self")/../foam-env.sh"
foam_env vs-openfoam.sh uncoupledKinematicParcelFoam
set -u

if [ "$foam_only" = 0 ]; then
    if [ -z "$SCG" ]; then
        SCG=$root/target/release/scg
        [ -x "$SCG" ] || (cd "$root" && cargo build --release --quiet)
    fi
    SCG=$(realpath "$SCG")
fi

py=(python3 "$root/cases/cyclone/vs_openfoam.py")
if [ "$quick" = 1 ]; then
    case_args+=(--duration 0.4)
    set_args+=(--set duration=0.4)
    : "${feed_scale:=0.25}"
fi
if [ -n "$feed_scale" ]; then
    case_args+=(--feed-scale "$feed_scale")
    set_args+=(--set "feed_scale=$feed_scale")
fi
echo "scene: $scene$([ "$quick" = 1 ] && echo " (--quick: duration 0.4 s)")${feed_scale:+ (feed_scale $feed_scale)}${dt:+ (dt $dt)}"
[ "$foam_only" = 1 ] && echo "scg: not run (--openfoam-only)" || echo "scg: $SCG ${scg_set[*]}"
echo "OpenFOAM: $(command -v uncoupledKinematicParcelFoam) ($(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
echo "cores: $(nproc)  load: $(cut -d' ' -f1-3 /proc/loadavg)  NICE='${NICE}'"

# --- OpenFOAM -------------------------------------------------------------------------------
rm -rf "$out/openfoam"
rc=0
"${py[@]}" case "$scene" "$out/openfoam" "${case_args[@]}" > "$out/runs.txt" || rc=$?
[ "$rc" = 0 ] || exit "$rc"
mapfile -t runs < "$out/runs.txt"
for d in "${runs[@]}"; do
    echo "== OpenFOAM: $d"
    if ! (cd "$d" && python3 "$root/bench/foam.py" run log.foam $NICE uncoupledKinematicParcelFoam > /dev/null); then
        tail -30 "$d/log.foam" >&2
        echo "vs-openfoam.sh: uncoupledKinematicParcelFoam failed in $d" >&2
        exit 1
    fi
    if grep -q "FOAM FATAL" "$d/log.foam"; then grep -A8 "FOAM FATAL" "$d/log.foam" >&2; exit 1; fi
done
"${py[@]}" grade "$out/openfoam" "$out/grade.json"
echo "wrote $out/grade.json"

# --- OpenFOAM on both cores -----------------------------------------------------------------
# The same case decomposed in two and run as its users run it on a 2-core machine (mpirun
# -np 2 ... -parallel). Debian's OpenFOAM has no scotch; `simple (2 1 1)` cuts the cyclone
# by a vertical plane through its axis, so that the swirl shares the parcels between the
# two halves (of the simple splits it ran fastest here: (2 1 1) 19.7 s, (1 2 1) 22.5 s,
# (1 1 2) 26.0 s wall on the full scene; --split changes it). The run fails when a
# processor holds no parcel at the end while the others hold at least 10 each.
decomposition="simple ($split)"
# copy_case SRC DST: a fresh copy of case SRC's inputs (no results) in DST.
copy_case() {
    rm -rf "$2"
    mkdir -p "$2"
    cp -r "$1/0" "$1/constant" "$1/system" "$2/"
}
mpi_flags=()
[ "$(id -u)" = 0 ] && mpi_flags+=(--allow-run-as-root)
par_dirs=()
for d in "${runs[@]}"; do
    p=$d-np2
    copy_case "$d" "$p"
    printf '%s\n' 'FoamFile' '{' '    version     2.0;' '    format      ascii;' \
        '    class       dictionary;' '    location    "system";' '    object      decomposeParDict;' \
        '}' 'numberOfSubdomains 2;' 'method          simple;' 'simpleCoeffs' '{' \
        "    n           ($split);" '}' > "$p/system/decomposeParDict"
    echo "== OpenFOAM, 2 ranks ($decomposition): $p"
    if ! (cd "$p" && decomposePar -force > log.decompose 2>&1); then
        tail -20 "$p/log.decompose" >&2
        echo "vs-openfoam.sh: decomposePar failed in $p" >&2
        exit 1
    fi
    if ! (cd "$p" && python3 "$root/bench/foam.py" run log.foam $NICE mpirun "${mpi_flags[@]}" -np 2 \
            uncoupledKinematicParcelFoam -parallel > /dev/null); then
        tail -30 "$p/log.foam" >&2
        echo "vs-openfoam.sh: mpirun -np 2 uncoupledKinematicParcelFoam -parallel failed in $p" >&2
        exit 1
    fi
    if grep -q "FOAM FATAL" "$p/log.foam"; then grep -A8 "FOAM FATAL" "$p/log.foam" >&2; exit 1; fi
    grep -E "^nProcs|^Slaves" "$p/log.foam" | head -2
    par_dirs+=("$p")
done
"${py[@]}" parallel "$out/openfoam-np2.json" "$decomposition" "${par_dirs[@]}"

# The other way OpenFOAM can use two cores: two serial runs at once, one per core (as a
# user running two cases, e.g. two particle densities): two copies of the first case, their
# rates summed.
pids=()
twin_dirs=()
for k in a b; do
    p=${runs[0]}-$k
    copy_case "${runs[0]}" "$p"
    twin_dirs+=("$p")
done
echo "== OpenFOAM, two serial runs at once: ${twin_dirs[*]}"
for p in "${twin_dirs[@]}"; do
    (cd "$p" && python3 "$root/bench/foam.py" run log.foam $NICE uncoupledKinematicParcelFoam > /dev/null) &
    pids+=($!)
done
for pid in "${pids[@]}"; do
    wait "$pid" || { echo "vs-openfoam.sh: a serial run at once failed (${twin_dirs[*]})" >&2; exit 1; }
done
"${py[@]}" concurrent "$out/openfoam-twice.json" "${twin_dirs[@]}"

if [ "$foam_only" = 1 ]; then
    echo
    echo "== OpenFOAM alone (--openfoam-only); load now $(cut -d' ' -f1-3 /proc/loadavg)"
    "${py[@]}" summary "$out/grade.json" "$out/openfoam-np2.json" "$out/openfoam-twice.json" | tee "$out/summary.txt"
    exit 0
fi

# --- scg ------------------------------------------------------------------------------------
for t in 1 2; do
    echo "== scg, $t thread(s)"
    if ! $NICE "$SCG" --threads "$t" run "$scene" --no-record --set coarse_grain.alpha=1 \
        "${set_args[@]}" "${scg_set[@]}" --summary-json "$out/scg-$t.json" > "$out/scg-$t.log" 2>&1; then
        tail -20 "$out/scg-$t.log" >&2
        echo "vs-openfoam.sh: scg run failed" >&2
        exit 1
    fi
    grep '^done:' "$out/scg-$t.log"
done

echo
echo "== grade efficiency (1 - escaped/fed) and speed; load now $(cut -d' ' -f1-3 /proc/loadavg)"
"${py[@]}" table "$out/grade.json" "$out/scg-1.json" "$out/scg-2.json" "$out/openfoam-np2.json" \
    "$out/openfoam-twice.json" | tee "$out/table.txt"
