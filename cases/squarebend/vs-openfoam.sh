#!/usr/bin/env bash
# OpenFOAM's squareBend duct side by side with OpenFOAM's own particle tracker: the
# scene's frozen U (OpenFOAM's noSlip walls as OpenFOAM wrote them), inlet-patch feed,
# sizes, density and drag in uncoupledKinematicParcelFoam (Debian's OpenFOAM v1912, one
# process, localInteraction: walls stick, outlet and inlet escape) and in scg; one table
# per size class of the fates (outlet, inlet, walls, airborne) with 95 % intervals.
#
#   bash cases/squarebend/vs-openfoam.sh [--scene cases/squarebend.toml] [--quick] [--out DIR]
#                                        [--scg PATH] [--no-scg] [--scg-set KEY=VALUE]
#
#   --scene FILE  the scg scene (default cases/squarebend.toml): [flow] kind = "openfoam",
#                 a fixed dt, one [[feeders]] with `patch` per [[groups]] size class,
#                 [flow.patches] walls / outlets / inlets with wall_model (or
#                 [flow.patches.interaction]) "stick" | "escape" | "rebound"
#   --quick       a check of the chain (seconds): 0.4 of the feed (200 per class, 2 per step) and
#                 0.1 s (--set feed_scale=0.4 --set duration=0.1 for scg)
#   --out DIR     results (default /tmp/scg-squarebend-vs-openfoam): grade.json
#                 (OpenFOAM's counts per class), scg.json (`scg run --summary-json`),
#                 fates.json and table.txt (the comparison), openfoam/ (the case, its log)
#   --scg PATH    scg binary (default target/release/scg, built with cargo if missing)
#   --no-scg      OpenFOAM only (its table; no scg run)
#   --scg-set KEY=VALUE  passed to scg as --set (repeatable); keys that change the physics
#                 break the like-for-like
#   --erosion P   the scene with its walls rebounding (e = 0.8) and [erosion] finnie with
#                 flow stress P Pa (written to DIR/scene-erosion.toml), for both codes
#   With [erosion] (model "finnie") in the scene: OpenFOAM's ParticleErosion on the same
#   patches, and the wear of both codes side by side in regions of REGION m (default
#   0.025): totals, the regions' shares, where each puts the most (erosion.txt, .json)
#   NICE="nice -n 5" prefixes both codes' runs alike (for a shared machine)
#
# Steps: installs OpenFOAM with apt when missing; writes the OpenFOAM case from the scene
# (cases/cyclone/vs_openfoam.py case: mesh and field of flow.case, patchInjection per class,
# sphereDrag, localInteraction from [flow.patches], patchPostProcessing on the stick and
# escape patches); runs uncoupledKinematicParcelFoam (bench/foam.py run); reads the fed
# (`parcels added`), escaped and stuck parcels (patchPostProcessing, checked against
# localInteraction's per-patch `Parcel fate` lines of the log) and those still moving
# (written active at the end) per class into grade.json; runs scg on the same scene
# (--no-record --summary-json); prints the table (cases/squarebend/vs_openfoam.py table).
set -eo pipefail
self=$(realpath "$0")
root=$(cd "$(dirname "$self")/../.." && pwd)
scene=$root/cases/squarebend.toml
out=/tmp/scg-squarebend-vs-openfoam
quick=0
no_scg=0
erosion_p=
case_args=()
set_args=()
scg_set=()
SCG=""
NICE=${NICE:-}
while [ $# -gt 0 ]; do
    case "$1" in
        --scene) scene=$2; shift ;;
        --out) out=$2; shift ;;
        --quick) quick=1 ;;
        --scg) SCG=$2; shift ;;
        --no-scg) no_scg=1 ;;
        --scg-set) scg_set+=(--set "$2"); shift ;;
        --erosion) erosion_p=$2; shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$self"; exit 0 ;;
        *) echo "vs-openfoam.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
[ -f "$scene" ] || { echo "vs-openfoam.sh: no scene $scene" >&2; exit 2; }
scene=$(realpath "$scene")
mkdir -p "$out"
out=$(realpath "$out")
if [ -n "$erosion_p" ]; then
    scene=$(python3 "$root/cases/squarebend/vs_openfoam.py" erosion-scene "$scene" "$out/scene-erosion.toml" \
        --flow-stress "$erosion_p")
    echo "--erosion: the walls rebound (e = 0.8) and wear by Finnie (p = $erosion_p Pa): $scene"
fi

# --- OpenFOAM (as cases/squarebend/build.sh) ------------------------------------------------
# shellcheck source=../foam-env.sh
source "$(dirname "$self")/../foam-env.sh"
foam_env vs-openfoam.sh uncoupledKinematicParcelFoam
set -u

if [ "$no_scg" = 0 ]; then
    if [ -z "$SCG" ]; then
        SCG=$root/target/release/scg
        [ -x "$SCG" ] || (cd "$root" && cargo build --release --quiet)
    fi
    SCG=$(realpath "$SCG")
fi

cyc=(python3 "$root/cases/cyclone/vs_openfoam.py")
py=(python3 "$root/cases/squarebend/vs_openfoam.py")
if [ "$quick" = 1 ]; then
    case_args+=(--duration 0.1 --feed-scale 0.4)
    set_args+=(--set duration=0.1 --set feed_scale=0.4)
fi
echo "scene: $scene$([ "$quick" = 1 ] && echo " (--quick: duration 0.1 s, feed_scale 0.4)")"
[ "$no_scg" = 0 ] && echo "scg: $SCG ${scg_set[*]}"
echo "OpenFOAM: $(command -v uncoupledKinematicParcelFoam) ($(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
echo "cores: $(nproc)  load: $(cut -d' ' -f1-3 /proc/loadavg)  NICE='${NICE}'"

# --- OpenFOAM -------------------------------------------------------------------------------
rm -rf "$out/openfoam"
rc=0
"${cyc[@]}" case "$scene" "$out/openfoam" "${case_args[@]}" > "$out/runs.txt" || rc=$?
[ "$rc" = 0 ] || exit "$rc"
mapfile -t runs < "$out/runs.txt"
for d in "${runs[@]}"; do
    echo "== OpenFOAM: $d"
    t0=$(date +%s.%N)
    if ! (cd "$d" && python3 "$root/bench/foam.py" run log.foam $NICE uncoupledKinematicParcelFoam > /dev/null); then
        tail -30 "$d/log.foam" >&2
        echo "vs-openfoam.sh: uncoupledKinematicParcelFoam failed in $d" >&2
        exit 1
    fi
    if grep -q "FOAM FATAL" "$d/log.foam"; then grep -A8 "FOAM FATAL" "$d/log.foam" >&2; exit 1; fi
    printf '   %.1f s wall, %s s CPU (ExecutionTime)\n' "$(echo "$(date +%s.%N) - $t0" | bc)" \
        "$(grep '^ExecutionTime' "$d/log.foam" | tail -1 | awk '{print $3}')"
done
"${cyc[@]}" grade "$out/openfoam" "$out/grade.json"
echo "wrote $out/grade.json"
python3 -c 'import json, sys; [print("  note:", n) for n in json.load(open(sys.argv[1]))["notes"][:-5]]' "$out/grade.json"

if [ "$no_scg" = 1 ]; then
    echo
    "${py[@]}" openfoam "$out/grade.json" --json "$out/fates.json" | tee "$out/table.txt"
    exit 0
fi

# --- scg ------------------------------------------------------------------------------------
echo "== scg"
# with [erosion] (Finnie): scg's wear per face, beside OpenFOAM's ParticleErosion below
erosion=$(python3 -c 'import sys, tomllib; print(1 if "erosion" in tomllib.load(open(sys.argv[1], "rb")) else 0)' "$scene")
erosion_args=()
[ "$erosion" = 1 ] && erosion_args=(--erosion-csv "$out/scg-erosion.csv")
if ! $NICE "$SCG" run "$scene" --no-record "${set_args[@]}" "${scg_set[@]}" "${erosion_args[@]}" \
        --summary-json "$out/scg.json" > "$out/scg.log" 2>&1; then
    tail -20 "$out/scg.log" >&2
    echo "vs-openfoam.sh: scg run failed ($out/scg.log)" >&2
    exit 1
fi
grep '^done:' "$out/scg.log" || true

echo
echo "== fates per class; load now $(cut -d' ' -f1-3 /proc/loadavg)"
"${py[@]}" table "$out/grade.json" "$out/scg.json" --plan "$out/openfoam/plan.json" --json "$out/fates.json" \
    | tee "$out/table.txt"

if [ "$erosion" = 1 ]; then
    echo
    echo "== erosion (OpenFOAM's ParticleErosion, scg's [erosion] finnie)"
    for d in "${runs[@]}"; do
        [ -d "$d/0/C" ] || [ -f "$d/0/C" ] || (cd "$d" && postProcess -func writeCellCentres -time 0 > log.centres 2>&1)
        last=$(ls -d "$d"/[0-9]* | sort -t/ -k1 -g | tail -1)
        for t in "$d"/[0-9]*; do
            [ -f "$t/kinematicCloudQ" ] && last=$t
        done
        "${py[@]}" erosion "$last" "$d/0/C" "$out/scg-erosion.csv" --region "${REGION:-0.025}" \
            --json "$out/erosion.json" | tee "$out/erosion.txt"
    done
fi
