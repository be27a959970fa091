#!/usr/bin/env bash
# Build the air flow of the OpenFOAM "MPPICFoam/cyclone" tutorial geometry for scg.
#
#   bash cases/cyclone/build.sh [--coarse|--full] [--layers N] [--out DIR] [--iterations N]
#                               [--np N] [--keep]
#
#   --coarse      (default) the tutorial's mesh: background blocks 33x33x63 (dx = 33 mm),
#                 snappyHexMesh at level 0, 30.8k cells; simpleFoam 800 iterations, U, k and
#                 omega averaged over the last 400; serial
#   --full        background blocks 66x66x126 (dx = 17 mm), 248k cells; 1000 iterations,
#                 averaged over the last 500, on --np processes (default 2: decomposePar +
#                 mpirun -np 2 + reconstructPar); about 1.2 s CPU per iteration and process,
#                 so about 20 minutes on 2 idle cores; 23 MB, not committed
#   --layers N    N inflation layers on the walls (snappyHexMesh addLayers: expansion 1.2,
#                 the outermost 0.4 of the cell outside, none thinner than 0.1 of it), so the
#                 wall-adjacent cells' centres sit in the log layer (y+ of tens, not hundreds);
#                 checkMesh must still say "Mesh OK."; 0 (default): none, the tutorial's
#   --out DIR     where the case scg reads goes (default cases/cyclone/coarse or .../full);
#                 it is replaced
#   --iterations  SIMPLE iterations (simpleFoam stops earlier when the residualControl
#                 targets of system/fvSolution are met; in this geometry they are not)
#   --average-from  first iteration of the averages UMean, kMean, omegaMean (default: half
#                 the iterations)
#   --np          processes for simpleFoam (1 = serial)
#   --model M     the RAS model: kOmegaSST (default), or a Reynolds-stress model that holds
#                 a cyclone's swirl better, LRR or SSG (R and epsilon solved, wall
#                 functions kqRWallFunction / epsilonWallFunction, relaxation 0.5; the
#                 export then carries RMean, epsilonMean and kMean (the average of
#                 k = tr(R)/2) instead of omega: [dispersion] k = "kMean",
#                 epsilon = "epsilonMean")
#   --keep        keep the OpenFOAM working directory (printed) instead of deleting it
#
# The summary (summary.txt) ends with the pressure drop: the static and total pressure
# (p, p + |U|²/2, averaged over the same iterations as U) area-averaged over the inlet and
# the outlet, and their differences in Pa (ρ = 1.2 kg/m³).
#
# Steps: install OpenFOAM (Debian's openfoam + openfoam-examples) with apt if missing;
# copy the tutorial's geometry (resources/geometry/cyclone.stl.gz), blockMeshDict and
# snappyHexMeshDict into a fresh case; blockMesh; snappyHexMesh -overwrite; checkMesh (the
# build fails unless it says "Mesh OK."); simpleFoam (steady RANS, k-omega SST, air
# nu = 1.5e-5 m^2/s, inlet 10 m/s as in the tutorial; template/ holds the dictionaries);
# then copies constant/polyMesh, the final U, k, omega, nut and the averages UMean, kMean,
# omegaMean (fieldAverage over the iterations from --average-from on; binary, gzipped), the
# STL (constant/triSurface), the case's dictionaries and a log summary to --out. k and omega
# (kMean, omegaMean) are the turbulence fields of scg's turbulent dispersion
# ([dispersion] model = "stochastic_ras"; epsilon = 0.09 k omega); nut is the last
# iteration's eddy viscosity (there is no average of it).
set -eo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
variant=coarse
out=""
iterations=""
average_from=""
np=""
layers=0
keep=0
model=kOmegaSST
while [ $# -gt 0 ]; do
    case "$1" in
        --coarse) variant=coarse ;;
        --full) variant=full ;;
        --out) out="$2"; shift ;;
        --iterations) iterations="$2"; shift ;;
        --np) np="$2"; shift ;;
        --layers) layers="$2"; shift ;;
        --average-from) average_from="$2"; shift ;;
        --keep) keep=1 ;;
        --model) model="$2"; shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
case "$model" in
    kOmegaSST|LRR|SSG) ;;
    *) echo "build.sh: --model $model: kOmegaSST, LRR or SSG" >&2; exit 2 ;;
esac
if [ "$variant" = coarse ]; then
    blocks="33 33 63"; : "${iterations:=800}"; : "${np:=1}"
else
    blocks="66 66 126"; : "${iterations:=1000}"; : "${np:=2}"
fi
: "${average_from:=$((iterations / 2))}"
: "${out:=$here/$variant}"
mkdir -p "$(dirname "$out")"
out="$(cd "$(dirname "$out")" && pwd)/$(basename "$out")"

# --- OpenFOAM ---------------------------------------------------------------------
# shellcheck source=../foam-env.sh
source "$here/../foam-env.sh"
examples=$foam_examples
foam_env build.sh simpleFoam "$examples/lagrangian/MPPICFoam/cyclone"
tutorial="$examples/lagrangian/MPPICFoam/cyclone"
stl="$examples/resources/geometry/cyclone.stl.gz"

# --- case ---------------------------------------------------------------------------
work="$(mktemp -d "${TMPDIR:-/tmp}/scg-cyclone-$variant.XXXXXX")"
[ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
echo "== $variant: working in $work"
cp -r "$here/template/." "$work/"
mkdir -p "$work/constant/triSurface"
cp "$stl" "$work/constant/triSurface/"
gunzip "$work/constant/triSurface/cyclone.stl.gz"
# the tutorial's background mesh, at the variant's resolution
sed "s/(33 33 63)/($blocks)/" "$tutorial/system/blockMeshDict" > "$work/system/blockMeshDict"
grep -q "($blocks)" "$work/system/blockMeshDict" || { echo "build.sh: blockMeshDict: no (33 33 63) block" >&2; exit 1; }
# the tutorial's snappyHexMeshDict; room for the finer variant's cells per process
zcat "$tutorial/system/snappyHexMeshDict.gz" \
    | sed -e 's/maxLocalCells [0-9]*;/maxLocalCells 4000000;/' \
          -e 's/maxGlobalCells [0-9]*;/maxGlobalCells 8000000;/' > "$work/system/snappyHexMeshDict"
if [ "$layers" -gt 0 ]; then
    # inflation layers on the wall patch `walls` (the tutorial's dictionary adds none)
    python3 - "$work/system/snappyHexMeshDict" "$layers" <<'PY'
import re, sys
path, n = sys.argv[1], int(sys.argv[2])
s = open(path).read()
subs = [
    (r"addLayers\s+false;", "addLayers       true;"),
    (r"layers\s*\{\s*\}", "layers\n    {\n        walls { nSurfaceLayers %d; }\n    }" % n),
    (r"expansionRatio\s+[0-9.]+;", "expansionRatio 1.2;"),
    (r"finalLayerThickness\s+[0-9.]+;", "finalLayerThickness 0.4;"),
    (r"minThickness\s+[0-9.]+;", "minThickness 0.1;"),
]
for pat, rep in subs:
    s, k = re.subn(pat, rep, s, count=1)
    if k != 1:
        sys.exit(f"build.sh: snappyHexMeshDict: no match for {pat}")
open(path, "w").write(s)
PY
    echo "== $layers inflation layers on walls"
fi
sed -i -e "s/ITERATIONS/$iterations/g" -e "s/AVERAGE_START/$average_from/" "$work/system/controlDict"
if [ "$model" != kOmegaSST ]; then
    # a Reynolds-stress model: R and epsilon instead of k and omega
    python3 - "$work" "$model" <<'PY'
import re, sys
work, model = sys.argv[1], sys.argv[2]
def edit(path, subs):
    s = open(path).read()
    for pat, rep in subs:
        s, k = re.subn(pat, rep, s, count=1)
        if k != 1:
            sys.exit(f"build.sh: {path}: no match for {pat}")
    open(path, "w").write(s)
edit(f"{work}/constant/turbulenceProperties", [(r"RASModel\s+kOmegaSST;", f"RASModel        {model};")])
edit(f"{work}/system/fvSchemes", [
    (r"div\(phi,omega\)[^;]*;", "div(phi,R)      bounded Gauss upwind;\n    div(phi,epsilon) bounded Gauss upwind;\n    div(R)          Gauss linear;\n    div((nu*dev2(T(grad(U))))) Gauss linear;"),
    (r"grad\(omega\)[^;]*;", "grad(epsilon)   cellLimited Gauss linear 1;"),
])
edit(f"{work}/system/fvSolution", [
    (r'"\(U\|k\|omega\)"', '"(U|R|epsilon)"'),
    (r'"\(k\|omega\)"\s+1e-5;', '"(R|epsilon)"   1e-5;'),
    (r"U\s+0\.7;", "U               0.5;"),
    (r'"\.\*"\s+0\.7;', '".*"            0.5;'),
    (r"p\s+0\.3;", "p               0.2;"),
])
# averages of R and epsilon, and k = tr(R)/2 registered each iteration to average it
edit(f"{work}/system/controlDict", [
    (r"k \{ mean on; prime2Mean off; base iteration; \}\s*omega \{ mean on; prime2Mean off; base iteration; \}",
     "R { mean on; prime2Mean off; base iteration; }\n            epsilon { mean on; prime2Mean off; base iteration; }\n            \"turbulenceProperties:k\" { mean on; prime2Mean off; base iteration; }"),
    (r"    iterationAverage\n", "    kOfR\n    {\n        type            turbulenceFields;\n        libs            (\"libfieldFunctionObjects.so\");\n        executeControl  timeStep;\n        writeControl    writeTime;\n        fields          (k);\n    }\n    iterationAverage\n"),
])
k = 0.375
eps = 0.09 * k * 60.0
r = 2.0 * k / 3.0
head = "FoamFile {{ version 2.0; format ascii; class {c}; object {o}; }}\n"
open(f"{work}/0/R", "w").write(head.format(c="volSymmTensorField", o="R") + f"""
dimensions      [0 2 -2 0 0 0 0];
internalField   uniform ({r} 0 0 {r} 0 {r});
boundaryField
{{
    inlet   {{ type fixedValue; value uniform ({r} 0 0 {r} 0 {r}); }}
    outlet  {{ type inletOutlet; inletValue uniform ({r} 0 0 {r} 0 {r}); value uniform ({r} 0 0 {r} 0 {r}); }}
    walls   {{ type kqRWallFunction; value uniform ({r} 0 0 {r} 0 {r}); }}
}}
""")
open(f"{work}/0/epsilon", "w").write(head.format(c="volScalarField", o="epsilon") + f"""
dimensions      [0 2 -3 0 0 0 0];
internalField   uniform {eps};
boundaryField
{{
    inlet   {{ type fixedValue; value uniform {eps}; }}
    outlet  {{ type inletOutlet; inletValue uniform {eps}; value uniform {eps}; }}
    walls   {{ type epsilonWallFunction; value uniform {eps}; }}
}}
""")
PY
    echo "== RAS model $model (R, epsilon)"
fi
cat > "$work/system/decomposeParDict" <<DICT
FoamFile { version 2.0; format ascii; class dictionary; object decomposeParDict; }
numberOfSubdomains $np;
method          simple;         // Debian's OpenFOAM has no scotch; slabs along z
simpleCoeffs    { n (1 1 $np); delta 0.001; }
DICT

cd "$work"
step() { foam_step build.sh "$work" "$@"; }   # step NAME CMD...: cases/foam-env.sh
echo "== mesh (uptime: $(uptime | sed 's/.*load/load/'))"
step blockMesh blockMesh
step snappyHexMesh snappyHexMesh -overwrite
step checkMesh checkMesh
grep -q "Mesh OK." log.checkMesh || { echo "build.sh: checkMesh failed:" >&2; grep -i -B2 -A2 "\*\*\*" log.checkMesh >&2; trap - EXIT; exit 1; }
cells=$(awk '/^ *cells:/ {print $2; exit}' log.checkMesh)
grep -E "^ *(points|faces|cells):|non-orthogonality Max|Max skewness|Max aspect ratio" log.checkMesh | sed 's/^ */   /'

echo "== simpleFoam, $model, $iterations iterations max, $np process(es)"
if [ "$np" -gt 1 ]; then
    step decomposePar decomposePar
    mpi_root=""; [ "$(id -u)" -eq 0 ] && mpi_root=--allow-run-as-root   # containers, CI
    step simpleFoam mpirun $mpi_root -np "$np" --oversubscribe simpleFoam -parallel
    step reconstructPar reconstructPar -latestTime
else
    step simpleFoam simpleFoam
fi
final=$(ls -d [0-9]* | sort -g | tail -1)
[ -n "$final" ] && [ "$final" != 0 ] && [ -f "$final/U" ] && [ -f "$final/UMean" ] || { echo "build.sh: no final U written" >&2; trap - EXIT; exit 1; }
if [ "$model" = kOmegaSST ]; then turb="k omega nut kMean omegaMean"; else turb="R epsilon nut RMean epsilonMean turbulenceProperties:kMean"; fi
for f in $turb; do
    [ -f "$final/$f" ] || { echo "build.sh: no final $f written" >&2; trap - EXIT; exit 1; }
done
if [ "$model" != kOmegaSST ]; then
    # the average of k = tr(R)/2 under the name scg's scenes use
    mv "$final/turbulenceProperties:kMean" "$final/kMean"
fi
# the last iteration's initial residuals and the inlet/outlet volume flows
summary="$work/summary.txt"
{
    echo "variant: $variant; blocks ($blocks); inflation layers: $layers; cells: $cells; processes: $np"
    echo "turbulence: RAS $model, steady (simpleFoam, SIMPLEC), nu = 1.5e-5 m^2/s, inlet U = (-10 0 0) m/s"
    if [ "$layers" -gt 0 ]; then
        echo "layers added by snappyHexMesh (log.snappyHexMesh):"
        grep -A5 -E "^patch +faces +layers" log.snappyHexMesh | tail -6 | sed 's/^/   /'
    fi
    echo "final iteration: $final (of $iterations max)"
    if grep -q "reached convergence" log.simpleFoam; then grep "reached convergence" log.simpleFoam; fi
    if [ "$model" = kOmegaSST ]; then
        echo "UMean, kMean, omegaMean, pMean: U, k, omega, p averaged over iterations $average_from..$final"
    else
        echo "UMean, RMean, epsilonMean, kMean, pMean: U, R, epsilon, k = tr(R)/2, p averaged over iterations $average_from..$final"
    fi
    echo "initial residuals (first solve of each iteration): last; min..max over the averaged iterations"
    if [ "$model" = kOmegaSST ]; then solved="Ux Uy Uz p k omega"; else solved="Ux Uy Uz p Rxx epsilon"; fi
    for f in $solved; do
        awk -v f="$f" -v a="$average_from" '
            /^Time = / { t = $3; seen = 0 }
            $0 ~ ("Solving for " f ",") && !seen {
                seen = 1; r = $0; sub(/.*Initial residual = /, "", r); sub(/,.*/, "", r); r += 0
                last = r
                if (t >= a) { if (n == 0 || r < lo) lo = r; if (n == 0 || r > hi) hi = r; n++ }
            }
            END { printf "   %-6s %.2e; %.2e..%.2e\n", f, last, lo, hi }' log.simpleFoam
    done
    echo "continuity (last): $(grep 'continuity errors' log.simpleFoam | tail -1 | sed 's/^ *//')"
    echo "volume flow at the last iteration, sum(phi), m^3/s: inlet $(tail -1 postProcessing/inletFlow/0/surfaceFieldValue.dat | awk '{print $2}')," \
         "outlet $(tail -1 postProcessing/outletFlow/0/surfaceFieldValue.dat | awk '{print $2}')"
    # the pressure drop: the averaged static (kinematic) and total (Pa) pressures over the
    # inlet and the outlet (surfaceFieldValue areaAverage at the final time)
    pin=$(grep -v '^#' postProcessing/inletPressure/*/surfaceFieldValue.dat | tail -1)
    pout=$(grep -v '^#' postProcessing/outletPressure/*/surfaceFieldValue.dat | tail -1)
    echo "pressure, area-averaged over the patch (averaged fields): inlet p $(echo "$pin" | awk '{printf "%.4g", 1.2 * $2}') Pa, p_t $(echo "$pin" | awk '{printf "%.4g", $3}') Pa;" \
         "outlet p $(echo "$pout" | awk '{printf "%.4g", 1.2 * $2}') Pa, p_t $(echo "$pout" | awk '{printf "%.4g", $3}') Pa"
    echo "pressure drop inlet to outlet: static $(awk -v a="$pin" -v b="$pout" 'BEGIN { split(a, x); split(b, y); printf "%.1f", 1.2 * (x[2] - y[2]) }') Pa," \
         "total $(awk -v a="$pin" -v b="$pout" 'BEGIN { split(a, x); split(b, y); printf "%.1f", x[3] - y[3] }') Pa"
    echo "wall times (s):"
    cat timings
    echo "load: $(uptime | sed 's/.*load/load/')"
} > "$summary"
cat "$summary"

# --- the case scg reads ---------------------------------------------------------------
foam_export "$out" "$final" "U UMean p pMean k omega nut kMean omegaMean R RMean epsilon epsilonMean" \
    controlDict fvSchemes fvSolution blockMeshDict snappyHexMeshDict
mkdir -p "$out/constant/triSurface"
cp "$stl" "$out/constant/triSurface/"   # for [[walls]] kind = "mesh" (scg reads .stl.gz)
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
