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
cp "$tutorial/system/fvSchemes" "$work/system/"
python3 "$here/blockmesh.py" --factor "$factor" > "$work/system/blockMeshDict"
# the inlet velocity along +x
sed -i -E "/^ *inlet/,/\}/ s/uniform \(10 0 0\)/uniform ($velocity 0 0)/" "$work/0/U"
grep -q "uniform ($velocity 0 0)" "$work/0/U" || { echo "build.sh: could not set the inlet velocity in 0/U" >&2; exit 1; }
# the tutorial's fvSolution with a residualControl (the tutorial runs 500 iterations)
sed 's/^\( *\)consistent yes;/\1consistent yes;\n\1residualControl\n\1{\n\1    p               1e-4;\n\1    U               1e-5;\n\1    "(k|epsilon)"   1e-5;\n\1}/' \
    "$tutorial/system/fvSolution" > "$work/system/fvSolution"
grep -q residualControl "$work/system/fvSolution" || { echo "build.sh: fvSolution: no 'consistent yes;' to add residualControl to" >&2; exit 1; }
cat > "$work/system/controlDict" <<DICT
/*--------------------------------*- C++ -*----------------------------------*\\
  scg cases/elbow: steady air flow through a round pipe with a 90 degree elbow
\\*---------------------------------------------------------------------------*/
FoamFile
{
    version     2.0;
    format      ascii;
    class       dictionary;
    object      controlDict;
}
application     simpleFoam;
startFrom       startTime;
startTime       0;
stopAt          endTime;
endTime         $iterations;    // at most; residualControl (fvSolution) ends it earlier
deltaT          1;
writeControl    timeStep;
writeInterval   $iterations;    // only the final field is written (also on convergence)
purgeWrite      0;
writeFormat     binary;
writePrecision  8;
writeCompression off;           // v1912 ignores it for binary files: gzipped by build.sh
timeFormat      general;
timePrecision   6;
runTimeModifiable false;

functions
{
    // Volume flow through the inlet and the outlet (postProcessing/): continuity check
    inletFlow
    {
        type            surfaceFieldValue;
        libs            ("libfieldFunctionObjects.so");
        writeControl    timeStep;
        writeInterval   1;
        log             false;
        writeFields     false;
        regionType      patch;
        name            inlet;
        operation       sum;
        fields          (phi);
    }
    outletFlow
    {
        \$inletFlow;
        name            outlet;
    }
}
DICT

cd "$work"
step() { foam_step build.sh "$work" "$@"; }   # step NAME CMD...: cases/foam-env.sh
echo "== mesh (uptime: $(uptime | sed 's/.*load/load/'))"
grep -E "cells$" system/blockMeshDict | sed 's/^ */   /'
step blockMesh blockMesh
step checkMesh checkMesh
grep -q "Mesh OK." log.checkMesh || { echo "build.sh: checkMesh failed:" >&2; grep -i -B2 -A2 "\*\*\*" log.checkMesh >&2; trap - EXIT; exit 1; }
cells=$(awk '/^ *cells:/ {print $2; exit}' log.checkMesh)
grep -E "^ *(points|faces|cells):|non-orthogonality Max|Max skewness|Max aspect ratio" log.checkMesh | sed 's/^ */   /'
awk '/Checking patch topology/ {on = 1} on && /^ *(inlet|outlet|walls) / {print "   patch " $0} /Checking faceZone/ {on = 0}' log.checkMesh | sed 's/  */ /g'

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
    if grep -q "reached convergence" log.simpleFoam; then
        grep "reached convergence" log.simpleFoam | sed 's/^/   /'
    else
        echo "   residualControl targets not met: stopped at the iteration count"
    fi
    echo "initial residuals (first solve of each iteration): first; last"
    for f in Ux Uy Uz p k epsilon; do
        awk -v f="$f" '
            /^Time = / { seen = 0 }
            $0 ~ ("Solving for " f ",") && !seen {
                seen = 1; r = $0; sub(/.*Initial residual = /, "", r); sub(/,.*/, "", r); r += 0
                if (n++ == 0) first = r; last = r
            }
            END { printf "   %-8s %.2e; %.2e\n", f, first, last }' log.simpleFoam
    done
    echo "continuity (last): $(grep 'continuity errors' log.simpleFoam | tail -1 | sed 's/^ *//')"
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
rm -rf "$out"
mkdir -p "$out/constant/polyMesh" "$out/$final" "$out/system"
# OpenFOAM v1912 ignores writeCompression for binary files ("Disabled binary format
# compression"): gzip them here (scg reads gzipped binary files)
for f in points faces owner neighbour boundary; do
    gzip -9 -n -c "constant/polyMesh/$f" > "$out/constant/polyMesh/$f.gz"
done
for f in U k epsilon nut p; do
    [ -f "$final/$f" ] && gzip -9 -n -c "$final/$f" > "$out/$final/$f.gz"
done
cp constant/transportProperties constant/turbulenceProperties "$out/constant/"
cp system/controlDict system/fvSchemes system/fvSolution system/blockMeshDict "$out/system/"
cp "$summary" "$out/summary.txt"
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
