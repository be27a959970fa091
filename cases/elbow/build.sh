#!/usr/bin/env bash
# Build the air flow through a round pipe with one 90° elbow (cases/elbow.toml) for scg.
#
#   bash cases/elbow/build.sh [--coarse|--full] [--cells-factor F] [--out DIR]
#                             [--velocity U] [--iterations N] [--keep]
#
#   --coarse      (default) cases/elbow/blockmesh.py at its base counts: an O-grid of 320
#                 cells per cross-section (8 x 8 centre, 4 x 8 x 8 outer graded to the
#                 wall), 30 + 24 + 30 sections: 26 880 cells; -> cases/elbow/coarse (committed)
#   --full        every count doubled (215 040 cells) -> cases/elbow/full (not committed)
#   --cells-factor F  another factor for the cell counts (each rounded, at least 1)
#   --out DIR     where the case scg reads goes (default cases/elbow/<variant>); replaced
#   --velocity U  the inlet air velocity, m/s along +x (default 20: dilute-phase conveying)
#   --iterations N  SIMPLE iterations at most (default 2000); simpleFoam stops earlier when
#                 the residualControl targets (p 1e-4, U, k, epsilon 1e-5) are met
#   --keep        keep the OpenFOAM working directory (printed) instead of deleting it
#
# Geometry and mesh: cases/elbow/blockmesh.py (D = 50 mm, R = 1.5 D, 0.3 m legs,
# horizontal +x to vertical-up +y). Physics: OpenFOAM's own squareBend tutorial set-up
# (Debian openfoam-examples, incompressible/simpleFoam/squareBend; its patches are also
# called inlet, outlet and walls): steady simpleFoam (SIMPLEC), k-epsilon with wall
# functions, nu = 1.5e-5 m^2/s; inlet U fixedValue (U 0 0) (the tutorial's 10 replaced),
# k 5 % intensity, epsilon mixing length 5 mm; walls noSlip, kqRWallFunction,
# epsilonWallFunction, nutkWallFunction; outlet p = 0, inletOutlet U, k, epsilon; the
# tutorial's fvSchemes, its fvSolution with a residualControl added.
#
# Steps: install OpenFOAM (Debian's openfoam + openfoam-examples) with apt if missing;
# blockMesh; checkMesh (the build fails unless it says "Mesh OK."); simpleFoam; then
# copies constant/polyMesh, the final U, k, epsilon, nut, p (binary, gzipped), the case's
# dictionaries and a log summary (summary.txt) to --out.
set -eo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
variant=coarse
factor=""
out=""
iterations=2000
velocity=20
keep=0
while [ $# -gt 0 ]; do
    case "$1" in
        --coarse) variant=coarse ;;
        --full) variant=full ;;
        --cells-factor) factor="$2"; shift ;;
        --out) out="$2"; shift ;;
        --iterations) iterations="$2"; shift ;;
        --velocity) velocity="$2"; shift ;;
        --keep) keep=1 ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "$factor" ]; then
    if [ "$variant" = coarse ]; then factor=1; else factor=2; fi
fi
: "${out:=$here/$variant}"
mkdir -p "$(dirname "$out")"
out="$(cd "$(dirname "$out")" && pwd)/$(basename "$out")"

# --- OpenFOAM ---------------------------------------------------------------------
# shellcheck source=../foam-env.sh
source "$here/../foam-env.sh"
examples=$foam_examples
tutorial="$examples/incompressible/simpleFoam/squareBend"
foam_env build.sh simpleFoam "$tutorial"

# --- case ---------------------------------------------------------------------------
work="$(mktemp -d "${TMPDIR:-/tmp}/scg-elbow-$variant.XXXXXX")"
[ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
echo "== $variant (cell counts x $factor): working in $work"
mkdir -p "$work/system"
cp -r "$tutorial/0" "$tutorial/constant" "$work/"
rm -rf "$work/constant/triSurface"        # the tutorial's sampling planes only
python3 "$here/blockmesh.py" --factor "$factor" > "$work/system/blockMeshDict"
# the inlet velocity along +x
sed -i -E "/^ *inlet/,/\}/ s/uniform \(10 0 0\)/uniform ($velocity 0 0)/" "$work/0/U"
grep -q "uniform ($velocity 0 0)" "$work/0/U" || { echo "build.sh: could not set the inlet velocity in 0/U" >&2; exit 1; }
foam_squarebend_system "$tutorial" "$work" "scg cases/elbow: steady air flow through a round pipe with a 90 degree elbow" "$iterations"

cd "$work"
step() { foam_step build.sh "$work" "$@"; }   # step NAME CMD...: cases/foam-env.sh
echo "== mesh (uptime: $(uptime | sed 's/.*load/load/'))"
grep -E "cells$" system/blockMeshDict | sed 's/^ */   /'
step blockMesh blockMesh
step checkMesh checkMesh
foam_check_mesh build.sh

echo "== simpleFoam, k-epsilon, $iterations iterations at most (1 process)"
step simpleFoam simpleFoam
final=$(ls -d [0-9]* | sort -g | tail -1)
[ -n "$final" ] && [ "$final" != 0 ] && [ -f "$final/U" ] || { echo "build.sh: no final U written" >&2; trap - EXIT; exit 1; }
cpu=$(grep "^ExecutionTime" log.simpleFoam | tail -1 | awk '{print $3}')
# the last iteration's initial residuals and the inlet/outlet volume flows
summary="$work/summary.txt"
{
    echo "variant: $variant; cell counts x $factor of cases/elbow/blockmesh.py's; cells: $cells; processes: 1"
    echo "set-up from: $tutorial (OpenFOAM $(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
    echo "turbulence: RAS kEpsilon, steady (simpleFoam, SIMPLEC), nu = 1.5e-5 m^2/s, inlet U = ($velocity 0 0) m/s; walls noSlip"
    echo "final iteration: $final (of $iterations max)"
    foam_residuals log.simpleFoam Ux Uy Uz p k epsilon
    echo "volume flow at the last iteration, sum(phi), m^3/s: inlet $(tail -1 postProcessing/inletFlow/0/surfaceFieldValue.dat | awk '{print $2}')," \
         "outlet $(tail -1 postProcessing/outletFlow/0/surfaceFieldValue.dat | awk '{print $2}')" \
         "(pi/4 x 0.05^2 m^2 x $velocity m/s = $(python3 -c "import math; print(f'{math.pi / 4 * 0.05**2 * $velocity:.7g}')"))"
    echo "simpleFoam CPU time (ExecutionTime): $cpu s"
    echo "wall times (s):"
    cat timings
    echo "load: $(uptime | sed 's/.*load/load/')"
} > "$summary"
cat "$summary"

# --- the case scg reads ---------------------------------------------------------------
foam_export "$out" "$final" "U k epsilon nut p" controlDict fvSchemes fvSolution blockMeshDict
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
