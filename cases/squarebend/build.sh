#!/usr/bin/env bash
# Build the air flow of OpenFOAM's "squareBend" tutorial duct for scg.
#
#   bash cases/squarebend/build.sh [--coarse|--full] [--cells-factor F] [--out DIR]
#                                  [--iterations N] [--keep]
#
#   --coarse      (default) the tutorial's blockMeshDict with every block's cell count
#                 times 0.6: blocks (12 12 12), (120 12 12), 2 x (18 12 12), 24 192 cells
#                 (4.2 mm cubes); serial; -> cases/squarebend/coarse (committed)
#   --full        the tutorial's own counts (factor 1): 112 000 cells (2.5 mm); serial;
#                 -> cases/squarebend/full (not committed)
#   --cells-factor F  another factor for the cell counts (each rounded, at least 1)
#   --out DIR     where the case scg reads goes (default cases/squarebend/<variant>); it is
#                 replaced
#   --iterations N  SIMPLE iterations at most (default 2000); simpleFoam stops earlier when
#                 the residualControl targets (p 1e-4, U, k, epsilon 1e-5) are met
#   --keep        keep the OpenFOAM working directory (printed) instead of deleting it
#
# The tutorial: Debian's openfoam-examples, incompressible/simpleFoam/squareBend (the same
# blockMeshDict as compressible/rhoSimpleFoam/squareBend; the incompressible one is the
# air flow asked for: steady simpleFoam, k-epsilon, nu = 1.5e-5 m^2/s, inlet U = (10 0 0)
# m/s, walls noSlip with k/epsilon/nut wall functions, outlet p = 0 and inletOutlet U).
# Its 0/ and constant/ are used as they are; system/ is the tutorial's fvSchemes, its
# fvSolution with a residualControl added, and a controlDict of this script (binary
# output, written once at the end; the inlet and outlet volume flows as function objects;
# the tutorial's sampling function objects are left out).
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
keep=0
while [ $# -gt 0 ]; do
    case "$1" in
        --coarse) variant=coarse ;;
        --full) variant=full ;;
        --cells-factor) factor="$2"; shift ;;
        --out) out="$2"; shift ;;
        --iterations) iterations="$2"; shift ;;
        --keep) keep=1 ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "$factor" ]; then
    if [ "$variant" = coarse ]; then factor=0.6; else factor=1; fi
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
work="$(mktemp -d "${TMPDIR:-/tmp}/scg-squarebend-$variant.XXXXXX")"
[ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
echo "== $variant (cell counts x $factor): working in $work"
mkdir -p "$work/system"
cp -r "$tutorial/0" "$tutorial/constant" "$work/"
rm -rf "$work/constant/triSurface"        # the tutorial's sampling planes only
cp "$tutorial/system/fvSchemes" "$work/system/"
# the tutorial's blockMeshDict, every block's cell counts times the factor
python3 - "$tutorial/system/blockMeshDict" "$factor" > "$work/system/blockMeshDict" <<'PY'
import re, sys
text, f = open(sys.argv[1]).read(), float(sys.argv[2])
def scale(m):
    n = [max(1, round(int(x) * f)) for x in m.group(2).split()]
    return m.group(1) + "(" + " ".join(str(x) for x in n) + ")"
new, k = re.subn(r"(hex\s*\([0-9 ]+\)\s*\w+\s*)\(\s*([0-9]+\s+[0-9]+\s+[0-9]+)\s*\)", scale, text)
if k != 4:
    sys.exit(f"build.sh: expected 4 hex blocks in the tutorial's blockMeshDict, found {k}")
sys.stdout.write(new)
PY
# the tutorial's fvSolution with a residualControl (the tutorial runs 500 iterations)
sed 's/^\( *\)consistent yes;/\1consistent yes;\n\1residualControl\n\1{\n\1    p               1e-4;\n\1    U               1e-5;\n\1    "(k|epsilon)"   1e-5;\n\1}/' \
    "$tutorial/system/fvSolution" > "$work/system/fvSolution"
grep -q residualControl "$work/system/fvSolution" || { echo "build.sh: fvSolution: no 'consistent yes;' to add residualControl to" >&2; exit 1; }
cat > "$work/system/controlDict" <<DICT
/*--------------------------------*- C++ -*----------------------------------*\\
  scg cases/squarebend: steady air flow in OpenFOAM's squareBend tutorial duct
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
grep -E "^ *hex" system/blockMeshDict | sed 's/^ */   /'
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
    echo "variant: $variant; cell counts x $factor of the tutorial's; cells: $cells; processes: 1"
    echo "blocks: $(grep -E '^ *hex' system/blockMeshDict | sed -E 's/.*\) *([a-z0-9]+) *\(([0-9 ]+)\).*/\1 (\2)/' | paste -sd ';' | sed 's/;/; /g')"
    echo "tutorial: $tutorial (OpenFOAM $(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
    echo "turbulence: RAS kEpsilon, steady (simpleFoam, SIMPLEC), nu = 1.5e-5 m^2/s, inlet U = (10 0 0) m/s; walls noSlip"
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
         "(0.05 x 0.05 m x 10 m/s = 0.025)"
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
