#!/usr/bin/env bash
# An unsteady air flow in the cyclone for scg's `[flow] series` (issue 56): pimpleFoam with the
# tutorial's own LES model (kEqn, cubeRootVol, as lagrangian/MPPICFoam/cyclone) on the
# committed coarse mesh, started from the steady k-omega SST field (cases/cyclone/coarse).
#
#   bash cases/cyclone/build-series.sh [--out DIR] [--spin-up S] [--window S] [--every S]
#                                      [--max-co C] [--keep]
#
#   --out DIR     where the series goes (default cases/cyclone/les); replaced
#   --spin-up S   simulated seconds before the first snapshot written (default 1.5: about
#                 one mean residence time V/Q = 1.45 s, from the steady field)
#   --window S    simulated seconds of snapshots after the spin-up (default 1.0)
#   --every S     snapshot spacing (default 0.01 s); the exported folders are renamed to
#                 the time since the window's start (0, 0.01, ...), so scg's t = 0 is the
#                 first snapshot
#   --max-co C    largest Courant number of the adaptive time step (default 0.7)
#   --export-every N  export every N-th written snapshot (default 1); a coarser export for
#                 a small committed series
#   --ascii P     export the snapshots in ASCII with P significant digits (foamFormatConvert;
#                 gzipped about half the size of binary: the committed series uses 6)
#   --fields "U k"  the fields exported in every folder (default U and k)
#   --keep        keep the OpenFOAM working directory (printed)
#   --reuse WORK  export from a working directory kept by an earlier --keep run (same
#                 --spin-up), without running pimpleFoam again
#
# Each exported folder holds U (the resolved velocity) and k (the sub-grid kinetic energy of
# kEqn; --fields), binary (or --ascii) and gzipped; the last one also holds UMean and UPrime2Mean, the time average
# and the resolved Reynolds stress over the window (fieldAverage). The mesh is the coarse
# steady case's (constant/polyMesh is a relative link to it). summary.txt: time steps, Courant
# numbers, the inlet/outlet flows, wall times.
set -eo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="$here/les"
spin_up=1.5
window=1.0
every=0.01
max_co=0.7
export_every=1
keep=0
ascii=""
reuse=""
fields="U k"
while [ $# -gt 0 ]; do
    case "$1" in
        --out) out="$2"; shift ;;
        --spin-up) spin_up="$2"; shift ;;
        --window) window="$2"; shift ;;
        --every) every="$2"; shift ;;
        --max-co) max_co="$2"; shift ;;
        --export-every) export_every="$2"; shift ;;
        --keep) keep=1 ;;
        --ascii) ascii="$2"; shift ;;
        --reuse) reuse="$2"; shift ;;
        --fields) fields="$2"; shift ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build-series.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
steady="$here/coarse"
[ -f "$steady/constant/polyMesh/points.gz" ] || { echo "build-series.sh: no steady case in $steady (bash cases/cyclone/build.sh)" >&2; exit 1; }
mkdir -p "$(dirname "$out")"
out="$(cd "$(dirname "$out")" && pwd)/$(basename "$out")"

# shellcheck source=../foam-env.sh
source "$here/../foam-env.sh"
foam_env build-series.sh pimpleFoam

end=$(echo "$spin_up + $window" | bc -l)

# A fresh OpenFOAM case in $work: the steady case's mesh, its mean velocity as U at t = 0,
# the LES model's fields and dictionaries.
write_case() {
    mkdir -p "$work/constant/polyMesh" "$work/system" "$work/0"
    for f in points faces owner neighbour boundary; do
        zcat "$steady/constant/polyMesh/$f.gz" > "$work/constant/polyMesh/$f"
    done
    cp "$steady/constant/transportProperties" "$work/constant/"
    steady_final=$(cd "$steady" && ls -d [0-9]* | sort -g | tail -1)
    # the initial velocity: the steady field's average (its cell values) under the name U, with
    # the steady case's boundary conditions (template/0/U; fieldAverage writes "calculated")
    python3 - "$steady/$steady_final/UMean.gz" "$here/template/0/U" "$work/0/U" <<'PY'
import gzip, re, sys
data = gzip.open(sys.argv[1]).read()
data, n = re.subn(rb"object\s+UMean;", b"object      U;", data, count=1)
if n != 1:
    sys.exit("build-series.sh: UMean: no 'object UMean;' header")
cut = data.index(b"boundaryField")
bcs = open(sys.argv[2], "rb").read()
bcs = bcs[bcs.index(b"boundaryField"):]
open(sys.argv[3], "wb").write(data[:cut] + bcs)
PY
    foam_header() { printf 'FoamFile { version 2.0; format ascii; class %s; object %s; }\n' "$1" "$2"; }
    { foam_header volScalarField p; cat <<'F'
dimensions      [0 2 -2 0 0 0 0];
internalField   uniform 0;
boundaryField
{
    inlet   { type zeroGradient; }
    outlet  { type fixedValue; value uniform 0; }
    walls   { type zeroGradient; }
}
F
    } > "$work/0/p"
    { foam_header volScalarField k; cat <<'F'
dimensions      [0 2 -2 0 0 0 0];
internalField   uniform 0.375;
boundaryField
{
    inlet   { type fixedValue; value uniform 0.375; }
    outlet  { type inletOutlet; inletValue uniform 0.375; value uniform 0.375; }
    walls   { type kqRWallFunction; value uniform 0.375; }
}
F
    } > "$work/0/k"
    { foam_header volScalarField nut; cat <<'F'
dimensions      [0 2 -1 0 0 0 0];
internalField   uniform 0;
boundaryField
{
    inlet   { type calculated; value uniform 0; }
    outlet  { type calculated; value uniform 0; }
    walls   { type nutkWallFunction; value uniform 0; }
}
F
    } > "$work/0/nut"
    { foam_header dictionary turbulenceProperties; cat <<'F'
simulationType  LES;
LES
{
    LESModel        kEqn;           // the MPPICFoam/cyclone tutorial's model
    turbulence      on;
    printCoeffs     on;
    delta           cubeRootVol;
    cubeRootVolCoeffs { deltaCoeff 1; }
}
F
    } > "$work/constant/turbulenceProperties"
    { foam_header dictionary fvSchemes; cat <<'F'
ddtSchemes      { default backward; }
gradSchemes     { default Gauss linear; grad(U) cellLimited Gauss linear 1; }
divSchemes
{
    default         none;
    div(phi,U)      Gauss LUST grad(U);
    div(phi,k)      Gauss limitedLinear 1;
    div((nuEff*dev2(T(grad(U))))) Gauss linear;
}
laplacianSchemes { default Gauss linear limited corrected 0.5; }
interpolationSchemes { default linear; }
snGradSchemes   { default limited corrected 0.5; }
wallDist        { method meshWave; }
F
    } > "$work/system/fvSchemes"
    { foam_header dictionary fvSolution; cat <<'F'
solvers
{
    p       { solver GAMG; smoother GaussSeidel; tolerance 1e-6; relTol 0.01; }
    pFinal  { $p; relTol 0; }
    "(U|k)" { solver smoothSolver; smoother symGaussSeidel; tolerance 1e-7; relTol 0.1; }
    "(U|k)Final" { $U; relTol 0; }
}
PIMPLE
{
    nOuterCorrectors 1;
    nCorrectors     2;
    nNonOrthogonalCorrectors 1;
}
F
    } > "$work/system/fvSolution"
    { foam_header dictionary controlDict; cat <<F
application     pimpleFoam;
startFrom       startTime;
startTime       0;
stopAt          endTime;
endTime         $end;
deltaT          2e-4;
adjustTimeStep  yes;
maxCo           $max_co;
maxDeltaT       1e-3;
writeControl    adjustableRunTime;
writeInterval   $every;
purgeWrite      0;
writeFormat     binary;
writePrecision  8;
timeFormat      general;
timePrecision   8;
runTimeModifiable false;
functions
{
$(foam_flow_functions inlet outlet)
    windowAverage
    {
        type            fieldAverage;
        libs            ("libfieldFunctionObjects.so");
        timeStart       $spin_up;
        writeControl    writeTime;
        fields
        (
            U { mean on; prime2Mean on; base time; }
        );
    }
}
F
    } > "$work/system/controlDict"
}

if [ -n "$reuse" ]; then
    work="$(cd "$reuse" && pwd)"
    [ -f "$work/log.pimpleFoam" ] || { echo "build-series.sh: --reuse $reuse: no log.pimpleFoam" >&2; exit 1; }
    echo "== reusing $work (pimpleFoam not run)"
else
    work="$(mktemp -d "${TMPDIR:-/tmp}/scg-cyclone-les.XXXXXX")"
    [ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
    echo "== working in $work"
    write_case
fi
cd "$work"
step() { foam_step build-series.sh "$work" "$@"; }
if [ -z "$reuse" ]; then
    echo "== pimpleFoam, LES kEqn, 0 .. $end s (snapshots every $every s from $spin_up s), maxCo $max_co"
    step pimpleFoam pimpleFoam
fi

# --- the series scg reads: the window's snapshots, renamed to the time since its start ---
rm -rf "$out"
mkdir -p "$out/constant" "$out/system"
# the mesh is the steady case's: a relative link to it, not a second copy
ln -s "$(realpath --relative-to="$out/constant" "$steady/constant/polyMesh")" "$out/constant/polyMesh"
cp constant/transportProperties constant/turbulenceProperties "$out/constant/"
cp system/controlDict system/fvSchemes system/fvSolution "$out/system/"
times=$(ls -d [0-9]* | sort -g | awk -v s="$spin_up" '$1 + 0 >= s - 1e-9')
last=$(echo "$times" | tail -1)
# the folders to export: every --export-every-th, and the last
picked=$(echo "$times" | awk -v k="$export_every" -v last="$last" '(NR - 1) % k == 0 || $1 == last')
if [ -n "$ascii" ]; then
    # foamFormatConvert rewrites the picked folders in ASCII (a copy of the case's
    # controlDict with writeFormat ascii and the requested precision)
    cp system/controlDict system/controlDict.binary
    sed -i -e 's/^writeFormat .*/writeFormat     ascii;/' -e "s/^writePrecision .*/writePrecision  $ascii;/" system/controlDict
    step foamFormatConvert foamFormatConvert -noConstant -time "$(echo $picked | tr ' ' ',')"
    mv system/controlDict.binary system/controlDict
fi
format=binary; [ -n "$ascii" ] && format="ASCII, $ascii significant digits"
exported=0
for t in $picked; do
    rel=$(awk -v t="$t" -v s="$spin_up" 'BEGIN { printf "%.8g", t - s }')
    mkdir -p "$out/$rel"
    for f in $fields; do gzip -9 -n -c "$t/$f" > "$out/$rel/$f.gz"; done
    if [ "$t" = "$last" ]; then
        for f in UMean UPrime2Mean; do gzip -9 -n -c "$t/$f" > "$out/$rel/$f.gz"; done
    fi
    exported=$((exported + 1))
done
steps=$(grep -c '^Time = ' log.pimpleFoam)
{
    echo "unsteady: pimpleFoam, LES kEqn (cubeRootVol), backward in time, LUST for U; PIMPLE 1 outer, 2 correctors"
    echo "mesh: cases/cyclone/coarse (30.8k cells); initial U: its steady UMean; inlet U = (-10 0 0) m/s, k = 0.375"
    echo "simulated 0 .. $end s in $steps time steps (adaptive, maxCo $max_co); window $spin_up .. $end s"
    echo "exported: $exported snapshots, every $export_every of those written every $every s; folder names = t - $spin_up; fields $fields; $format"
    echo "Courant number (last step): $(grep '^Courant Number' log.pimpleFoam | tail -1)"
    echo "deltaT (last step): $(grep '^deltaT' log.pimpleFoam | tail -1)"
    echo "volume flow at the end, sum(phi), m^3/s: inlet $(tail -1 postProcessing/inletFlow/0/surfaceFieldValue.dat | awk '{print $2}')," \
         "outlet $(tail -1 postProcessing/outletFlow/0/surfaceFieldValue.dat | awk '{print $2}')"
    echo "wall times (s):"
    cat timings
    echo "load: $(uptime | sed 's/.*load/load/')"
} > "$out/summary.txt"
cat "$out/summary.txt"
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
