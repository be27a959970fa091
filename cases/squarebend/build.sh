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
foam_squarebend_system "$tutorial" "$work" "scg cases/squarebend: steady air flow in OpenFOAM's squareBend tutorial duct" "$iterations"

cd "$work"
step() { foam_step build.sh "$work" "$@"; }   # step NAME CMD...: cases/foam-env.sh
echo "== mesh (uptime: $(uptime | sed 's/.*load/load/'))"
grep -E "^ *hex" system/blockMeshDict | sed 's/^ */   /'
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
    echo "variant: $variant; cell counts x $factor of the tutorial's; cells: $cells; processes: 1"
    echo "blocks: $(grep -E '^ *hex' system/blockMeshDict | sed -E 's/.*\) *([a-z0-9]+) *\(([0-9 ]+)\).*/\1 (\2)/' | paste -sd ';' | sed 's/;/; /g')"
    echo "tutorial: $tutorial (OpenFOAM $(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
    echo "turbulence: RAS kEpsilon, steady (simpleFoam, SIMPLEC), nu = 1.5e-5 m^2/s, inlet U = (10 0 0) m/s; walls noSlip"
    echo "final iteration: $final (of $iterations max)"
    foam_residuals log.simpleFoam Ux Uy Uz p k epsilon
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
foam_export "$out" "$final" "U k epsilon nut p" controlDict fvSchemes fvSolution blockMeshDict
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
