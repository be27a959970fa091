#!/usr/bin/env bash
# Build the air flow of a deflector-wheel classifier slice (cases/wheel.toml) for scg: an
# OpenFOAM single-rotating-frame (SRF) solution, its relative velocity averaged in time
# (UrelMean).
#
#   bash cases/wheel/build.sh [--coarse|--full] [--mrf] [--cells-factor F] [--out DIR]
#                             [--rpm N] [--radial V] [--swirl W] [--end T] [--average-from T] [--keep]
#
#   --coarse      (default) cases/wheel/blockmesh.py at its base counts: 6 144 cells
#                 -> cases/wheel/coarse (committed)
#   --full        every count doubled (about 24 600 cells) -> cases/wheel/full (not committed)
#   --mrf         the same wheel as a frozen rotor: the absolute U by pimpleFoam with an
#                 MRF zone `rotor` (the blade ring, r = 35 to 50 mm; constant/MRFProperties)
#                 instead of the SRF, averaged the same way (UMean) -> cases/wheel/<variant>-mrf
#   --cells-factor F  another factor for the cell counts
#   --out DIR     where the case scg reads goes (default cases/wheel/<variant>); replaced
#   --rpm N       the wheel's speed, rev/min about +z (default 3000: tip speed 15.7 m/s)
#   --radial V    the air's inward radial velocity at the inlet circle r = 0.1 m, m/s
#                 (default 0.5: 1.0 m/s at the wheel radius, 3.14e-3 m^3/s per 10 mm slice)
#   --swirl W     the air's absolute tangential velocity at the inlet, m/s (default 7.854:
#                 a free vortex from there reaches the tip speed at the wheel radius)
#   --end T       the transient's end, s (default 0.4: four air residence times V/Q =
#                 0.096 s); the fields are averaged from --average-from (default 0.1 s)
#   --keep        keep the OpenFOAM working directory (printed) instead of deleting it
#
# Geometry and mesh: cases/wheel/blockmesh.py (24 radial blades from r = 35 to 50 mm, fines
# outlet r = 20 mm, inlet r = 100 mm, a 10 mm slice with empty front and back). Physics:
# OpenFOAM's own SRFSimpleFoam mixer tutorial set-up (Debian openfoam-examples,
# incompressible/SRFSimpleFoam/mixer): the frame turning at --rpm about +z through the
# origin (constant/SRFProperties), k-omega SST with wall functions, nu = 1.5e-5 m^2/s. The
# steady SRFSimpleFoam does not converge on this wheel (its residuals stall at 1e-2 with
# linearUpwind or upwind, relaxation 0.3-0.9, laminar too: the blade wakes shed), so the
# field is a time average of the transient SRFPimpleFoam (the rotor2D tutorial's schemes
# and solvers, Co <= 0.8) from --average-from to --end (fieldAverage: UrelMean, kMean,
# omegaMean, nutMean and the resolved fluctuations UrelPrime2Mean). Boundary conditions, in the
# rotating frame: inlet Urel cylindricalInletVelocity with radialVelocity -V and rpm equal
# to the absolute swirl's W/R3 minus the frame's (so the absolute inflow is V inward and W
# tangential), k and omega fixed (intensity 5 % of the absolute inflow speed: turbulence
# does not depend on the frame; mixing length 5 mm); blades noSlip (at rest
# in the frame: they turn with the wheel), kqRWallFunction, omegaWallFunction,
# nutkWallFunction; fines p = 0, pressureInletOutletVelocity, inletOutlet k and omega.
#
# Steps: install OpenFOAM (Debian's openfoam + openfoam-examples) with apt if missing;
# blockMesh; checkMesh (fails unless "Mesh OK."); SRFPimpleFoam; then copies
# constant/polyMesh, the averages and the final Urel, k, omega, nut, p (binary, gzipped),
# SRFProperties, the case's dictionaries and a log summary (summary.txt) to --out.
set -eo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
variant=coarse
factor=""
out=""
end=0.4
average_from=0.1
rpm=3000
radial=0.5
swirl=7.853981634
keep=0
mrf=0
while [ $# -gt 0 ]; do
    case "$1" in
        --coarse) variant=coarse ;;
        --full) variant=full ;;
        --mrf) mrf=1 ;;
        --cells-factor) factor="$2"; shift ;;
        --out) out="$2"; shift ;;
        --end) end="$2"; shift ;;
        --average-from) average_from="$2"; shift ;;
        --rpm) rpm="$2"; shift ;;
        --radial) radial="$2"; shift ;;
        --swirl) swirl="$2"; shift ;;
        --keep) keep=1 ;;
        -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
        *) echo "build.sh: unknown argument $1" >&2; exit 2 ;;
    esac
    shift
done
if [ -z "$factor" ]; then
    if [ "$variant" = coarse ]; then factor=1; else factor=2; fi
fi
suffix=""; [ "$mrf" = 1 ] && suffix=-mrf
: "${out:=$here/$variant$suffix}"
mkdir -p "$(dirname "$out")"
out="$(cd "$(dirname "$out")" && pwd)/$(basename "$out")"

# --- OpenFOAM ---------------------------------------------------------------------
# shellcheck source=../foam-env.sh
source "$here/../foam-env.sh"
tutorial="$foam_examples/incompressible/SRFSimpleFoam/mixer"
transient="$foam_examples/incompressible/SRFPimpleFoam/rotor2D"
foam_env build.sh SRFPimpleFoam "$transient"
# the SRF solves the relative velocity Urel with SRFPimpleFoam; the MRF the absolute U
# with pimpleFoam (the zone's terms from constant/MRFProperties)
if [ "$mrf" = 1 ]; then solver=pimpleFoam; ufield=U; else solver=SRFPimpleFoam; ufield=Urel; fi

# --- case ---------------------------------------------------------------------------
work="$(mktemp -d "${TMPDIR:-/tmp}/scg-wheel-$variant$suffix.XXXXXX")"
[ "$keep" = 1 ] || trap 'rm -rf "$work"' EXIT
echo "== $variant (cell counts x $factor): working in $work"
mkdir -p "$work/system" "$work/constant" "$work/0"
cp "$tutorial/constant/transportProperties" "$tutorial/constant/turbulenceProperties" "$work/constant/"
if [ "$mrf" = 1 ]; then
    python3 "$here/blockmesh.py" --factor "$factor" --zone rotor > "$work/system/blockMeshDict"
else
    python3 "$here/blockmesh.py" --factor "$factor" > "$work/system/blockMeshDict"
fi
# inflow numbers: the relative rpm at the inlet, |Urel| there, k and omega
read -r rel_rpm urel k omega < <(python3 - "$rpm" "$radial" "$swirl" <<'PY'
import math, sys
rpm, v, w = map(float, sys.argv[1:])
r3 = 0.1
rel = (w / r3) * 60 / (2 * math.pi) - rpm          # absolute swirl's rpm minus the frame's
u = math.hypot(v, rel * 2 * math.pi / 60 * r3)      # |Urel| at the inlet
k = 1.5 * (0.05 * math.hypot(v, w)) ** 2            # 5 % of the absolute inflow speed
omega = math.sqrt(k) / (0.09 ** 0.25 * 0.005)
print(f"{rel:.9g} {u:.6g} {k:.6g} {omega:.6g}")
PY
)
header() {
    printf 'FoamFile\n{\n    version     2.0;\n    format      ascii;\n    class       %s;\n    object      %s;\n}\n' "$1" "$2"
}
if [ "$mrf" = 1 ]; then
{
    header dictionary MRFProperties
    cat <<DICT
MRF1
{
    cellZone            rotor;
    active              yes;
    nonRotatingPatches  ();
    origin              (0 0 0);
    axis                (0 0 1);
    omega               $(python3 -c "import math; print(f'{$rpm * 2 * math.pi / 60:.12g}')");   // $rpm rpm
}
DICT
} > "$work/constant/MRFProperties"
else
{
    header dictionary SRFProperties
    cat <<DICT
SRFModel        rpm;
origin          (0 0 0);
axis            (0 0 1);
rpmCoeffs
{
    rpm         $rpm;
}
DICT
} > "$work/constant/SRFProperties"
fi
if [ "$mrf" = 1 ]; then inlet_rpm=$(python3 -c "print(f'{$rel_rpm + $rpm:.9g}')"); else inlet_rpm=$rel_rpm; fi
{
    header volVectorField $ufield
    cat <<DICT
dimensions      [0 1 -1 0 0 0 0];
internalField   uniform (0 0 0);
boundaryField
{
    inlet
    {
        // absolute inflow: $radial m/s inward, $swirl m/s tangential (for the SRF's Urel,
        // in the frame turning at $rpm rev/min, the tangential part minus Omega x r)
        type            cylindricalInletVelocity;
        origin          (0 0 0);
        axis            (0 0 1);
        axialVelocity   0;
        radialVelocity  -$radial;
        rpm             $inlet_rpm;
        value           uniform (0 0 0);
    }
    fines
    {
        type            pressureInletOutletVelocity;
        value           uniform (0 0 0);
    }
    blades
    {
        type            noSlip;   // at rest in the SRF; moved at Omega x r by the MRF zone
    }
    frontAndBack
    {
        type            empty;
    }
}
DICT
} > "$work/0/$ufield"
scalar_field() {  # NAME DIMENSIONS VALUE WALLTYPE
    header volScalarField "$1"
    cat <<DICT
dimensions      $2;
internalField   uniform $3;
boundaryField
{
    inlet
    {
        type            $([ "$1" = p ] && echo zeroGradient || ([ "$1" = nut ] && echo calculated || echo fixedValue));
        value           uniform $3;
    }
    fines
    {
        type            $([ "$1" = p ] && echo fixedValue || ([ "$1" = nut ] && echo calculated || echo inletOutlet));
        $([ "$1" = p ] || [ "$1" = nut ] || echo "inletValue      uniform $3;")
        value           uniform $3;
    }
    blades
    {
        type            $4;
        value           uniform $3;
    }
    frontAndBack
    {
        type            empty;
    }
}
DICT
}
scalar_field p "[0 2 -2 0 0 0 0]" 0 zeroGradient > "$work/0/p"
scalar_field k "[0 2 -2 0 0 0 0]" "$k" kqRWallFunction > "$work/0/k"
scalar_field omega "[0 0 -1 0 0 0 0]" "$omega" omegaWallFunction > "$work/0/omega"
scalar_field nut "[0 2 -1 0 0 0 0]" 0 nutkWallFunction > "$work/0/nut"

# the transient tutorial's schemes and solvers (its epsilon entries made omega's)
sed 's/div(phi,epsilon) Gauss limitedLinear 1;/div(phi,omega) Gauss limitedLinear 1;/' \
    "$transient/system/fvSchemes" > "$work/system/fvSchemes"
printf '\nwallDist\n{\n    method meshWave;\n}\n' >> "$work/system/fvSchemes"
sed -e 's/epsilon/omega/g' -e 's/pRefCell        0;/pRefCell        0;\n    momentumPredictor yes;/' \
    "$transient/system/fvSolution" > "$work/system/fvSolution"
grep -q "div(phi,omega)" "$work/system/fvSchemes" || { echo "build.sh: fvSchemes: no omega scheme" >&2; exit 1; }
# pimpleFoam's velocity is U
[ "$mrf" = 1 ] && sed -i 's/Urel/U/g' "$work/system/fvSchemes" "$work/system/fvSolution"
{
    header dictionary controlDict
    cat <<DICT
application     $solver;
startFrom       startTime;
startTime       0;
stopAt          endTime;
endTime         $end;
deltaT          5e-5;
writeControl    runTime;
writeInterval   $end;           // only the final fields and their averages
purgeWrite      0;
writeFormat     binary;
writePrecision  8;
writeCompression off;
timeFormat      general;
timePrecision   6;
runTimeModifiable false;
adjustTimeStep  yes;
maxCo           0.8;
maxDeltaT       1e-3;

functions
{
    average
    {
        type            fieldAverage;
        libs            ("libfieldFunctionObjects.so");
        writeControl    writeTime;
        timeStart       $average_from;
        fields
        (
            $ufield { mean on; prime2Mean on; base time; }
            k     { mean on; prime2Mean off; base time; }
            omega { mean on; prime2Mean off; base time; }
            nut   { mean on; prime2Mean off; base time; }
        );
    }
$(foam_flow_functions inlet fines)
}
DICT
} > "$work/system/controlDict"

cd "$work"
step() { foam_step build.sh "$work" "$@"; }   # step NAME CMD...: cases/foam-env.sh
echo "== mesh (uptime: $(uptime | sed 's/.*load/load/'))"
step blockMesh blockMesh
step checkMesh checkMesh
foam_check_mesh build.sh

echo "== $solver, k-omega SST, $rpm rpm, 0 to $end s, averaged from $average_from s (1 process)"
step "$solver" "$solver"
final=$(ls -d [0-9]* | sort -g | tail -1)
[ -n "$final" ] && [ "$final" != 0 ] && [ -f "$final/${ufield}Mean" ] || { echo "build.sh: no final ${ufield}Mean written" >&2; trap - EXIT; exit 1; }
cpu=$(grep "^ExecutionTime" "log.$solver" | tail -1 | awk '{print $3}')
summary="$work/summary.txt"
{
    echo "variant: $variant; cell counts x $factor of cases/wheel/blockmesh.py's; cells: $cells; processes: 1"
    echo "set-up from: $tutorial (OpenFOAM $(dpkg-query -W -f='${Version}' openfoam 2>/dev/null || echo '?'))"
    if [ "$mrf" = 1 ]; then echo "MRF zone rotor (the blade ring): $rpm rpm about +z through the origin (frozen rotor, absolute U)"; else echo "SRF: $rpm rpm about +z through the origin"; fi
    echo "inflow (absolute) $radial m/s inward, $swirl m/s tangential at r = 0.1 m (relative rpm $rel_rpm, |Urel| $urel m/s, k $k, omega $omega)"
    echo "turbulence: RAS kOmegaSST, transient ($solver, Co <= 0.8), nu = 1.5e-5 m^2/s"
    echo "final time: $final s; averaged from $average_from s; time steps: $(grep -c '^Time = ' "log.$solver"); last $(grep '^deltaT' "log.$solver" | tail -1)"
    echo "last Courant: $(grep '^Courant' "log.$solver" | tail -1)"
    echo "volume flow at the last iteration, sum(phi), m^3/s: inlet $(tail -1 postProcessing/inletFlow/0/surfaceFieldValue.dat | awk '{print $2}')," \
         "fines $(tail -1 postProcessing/finesFlow/0/surfaceFieldValue.dat | awk '{print $2}')" \
         "(2 pi x 0.1 m x 0.01 m x $radial m/s = $(python3 -c "import math; print(f'{2 * math.pi * 0.1 * 0.01 * $radial:.7g}')"))"
    echo "$solver CPU time (ExecutionTime): $cpu s"
    echo "wall times (s):"
    cat timings
    echo "load: $(uptime | sed 's/.*load/load/')"
} > "$summary"
cat "$summary"

# --- the case scg reads ---------------------------------------------------------------
foam_export "$out" "$final" "${ufield}Mean kMean omegaMean nutMean $ufield k omega nut p" controlDict fvSchemes fvSolution blockMeshDict
if [ "$mrf" = 1 ]; then
    cp constant/MRFProperties "$out/constant/"
    gzip -9 -n -c constant/polyMesh/cellZones > "$out/constant/polyMesh/cellZones.gz"
else
    cp constant/SRFProperties "$out/constant/"
fi
echo "== wrote $out ($(du -sh "$out" | cut -f1))"
