#!/usr/bin/env bash
# Build the homogeneous-turbulence duct for scg and OpenFOAM (cases/duct.toml): a 2 m box
# duct of 5000 cells with a uniform air flow of 1 m/s and uniform k = 0.01 m²/s²,
# epsilon = 0.1 m²/s³ (cases/duct/make_case.py says why each value).
#
#   bash cases/duct/build.sh [--out DIR]     (default cases/duct/case, committed)
#
# Steps: install OpenFOAM (Debian's openfoam) with apt if missing; write the case
# (make_case.py); blockMesh (gzipped ASCII); checkMesh (fails unless "Mesh OK."); copy
# constant/polyMesh and 0/ to --out. Nothing is solved: the fields are the frozen flow.
set -eo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$here/case"
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
source "$here/../foam-env.sh"
foam_env build.sh blockMesh
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$here/make_case.py" "$work"
cd "$work"
foam_step build.sh "$work" blockMesh blockMesh
foam_step build.sh "$work" checkMesh checkMesh
grep -q "Mesh OK." log.checkMesh || { tail -30 log.checkMesh >&2; echo "build.sh: checkMesh failed" >&2; exit 1; }
rm -rf "$out"
mkdir -p "$out/constant" "$out/system"
cp -r constant/polyMesh "$out/constant/"
cp -r 0 "$out/"
cp system/blockMeshDict system/controlDict "$out/system/"
echo "wrote $out ($(grep -m1 'cells:' log.checkMesh | awk '{print $2}') cells)"
