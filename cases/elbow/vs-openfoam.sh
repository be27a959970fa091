#!/usr/bin/env bash
# The elbow (cases/elbow.toml) side by side with OpenFOAM's own particle tracker: the
# scene's frozen U, k and epsilon, inlet-patch feed, sizes, density, sphereDrag (scg:
# putnam), gravity, stochasticDispersionRAS (scg: stochastic_ras), rebound walls (e 0.8,
# mu 0) and ParticleErosion (Finnie, p 1 GPa) in uncoupledKinematicParcelFoam (Debian's
# OpenFOAM v1912, one process) and in scg. One command for the whole comparison:
#
#   bash cases/elbow/vs-openfoam.sh [--out DIR] [--quick] [--scg PATH] [--scg-set KEY=VALUE]
#
#   --out DIR   results (default /tmp/scg-elbow-vs-openfoam): the squareBend script's
#               table.txt (fates per class with 95 % intervals), erosion.txt (totals, 25 mm
#               cubes), and bend.txt / bend.json (cases/elbow/bend.py: the wear by zone
#               along the elbow, 30° of the bend and 50 mm of the legs, then 10° and 25 mm)
#   the other arguments go to cases/squarebend/vs-openfoam.sh (its --help), which does
#   the work: writes the OpenFOAM case from the scene, runs both codes, compares.
set -eo pipefail
self=$(realpath "$0")
here=$(dirname "$self")
root=$(cd "$here/../.." && pwd)
out=/tmp/scg-elbow-vs-openfoam
args=()
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out=$2; shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$self"; exit 0 ;;
        *) args+=("$1") ;;
    esac
    shift
done
mkdir -p "$out"
out=$(realpath "$out")
bash "$root/cases/squarebend/vs-openfoam.sh" --scene "$root/cases/elbow.toml" --out "$out" "${args[@]}"
d=$(head -1 "$out/runs.txt")
last=$(ls -d "$d"/[0-9]* | sort -t/ -k1 -g | tail -1)
echo
echo "== wear along the elbow"
python3 "$here/bend.py" "$last" "$d/0/C" "$out/scg-erosion.csv" --json "$out/bend.json" | tee "$out/bend.txt"
python3 "$here/bend.py" "$last" "$d/0/C" "$out/scg-erosion.csv" --bin 10 --leg-bin 25 \
    --json "$out/bend-fine.json" | tee -a "$out/bend.txt"
