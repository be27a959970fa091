# Sourced by the scripts that run OpenFOAM (cases/*/build.sh, cases/*/vs-openfoam.sh):
#   foam_env SCRIPT COMMAND [PATH]   installs Debian's openfoam and openfoam-examples with apt
#                                    when the bashrc, COMMAND or PATH (a tutorial folder) is
#                                    missing, sources the bashrc, and fails naming SCRIPT when
#                                    COMMAND is still not found
#   foam_step SCRIPT WORK NAME CMD…  runs CMD in the current folder, logs to log.NAME, prints
#                                    and appends to ./timings its wall time; on failure prints
#                                    the end of the log (in WORK) and exits
foam_etc=/usr/share/openfoam/etc/bashrc
foam_examples=/usr/share/doc/openfoam-examples/examples

foam_env() {
    local script=$1 cmd=$2 need=${3:-}
    if [ ! -f "$foam_etc" ] || ! command -v "$cmd" >/dev/null || { [ -n "$need" ] && [ ! -e "$need" ]; }; then
        echo "== installing OpenFOAM (Debian packages openfoam, openfoam-examples)"
        local sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
        $sudo apt-get update
        $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y --no-install-recommends \
            openfoam openfoam-examples
    fi
    # The Debian bashrc refers to unset variables and to helper scripts it does not ship.
    # (sourced with no arguments: the bashrc reads its arguments as settings or files to
    # source, and would source a script of the current folder named like our first one)
    set --
    # shellcheck disable=SC1090
    source "$foam_etc" >/dev/null 2>&1 || true
    command -v "$cmd" >/dev/null || { echo "$script: $cmd not found after sourcing $foam_etc" >&2; exit 1; }
}

foam_step() {
    local script=$1 work=$2 name=$3; shift 3
    local t0; t0=$(date +%s.%N)
    if ! "$@" > "log.$name" 2>&1; then
        echo "$script: $name failed; the end of $work/log.$name:" >&2
        tail -30 "log.$name" >&2
        trap - EXIT
        exit 1
    fi
    local t1; t1=$(date +%s.%N)
    printf '   %-16s %7.1f s\n' "$name" "$(echo "$t1 - $t0" | bc)" | tee -a timings
}

# The steady simpleFoam set-up the squareBend-based builds share (cases/squarebend,
# cases/elbow):
#   foam_squarebend_system TUTORIAL WORK TITLE ITERATIONS
#                                    the tutorial's fvSchemes, its fvSolution with a
#                                    residualControl (p 1e-4, U, k, epsilon 1e-5), and a
#                                    controlDict: binary output written once at the end,
#                                    the inlet and outlet sum(phi) function objects
#   foam_flow_functions IN OUT       the controlDict function objects summing phi over the
#                                    patches IN and OUT (postProcessing/<patch>Flow)
#   foam_check_mesh SCRIPT           checkMesh's summary lines (in the current folder);
#                                    fails unless "Mesh OK."; sets `cells`
#   foam_residuals LOG FIELD…        per field the first and last initial residuals
#   foam_export OUT FINAL FIELDS DICTS…  the case scg reads: polyMesh and FIELDS of time
#                                    FINAL gzipped (v1912 ignores writeCompression for
#                                    binary files), transport and turbulence properties,
#                                    system/DICTS, summary.txt
foam_squarebend_system() {
    local tutorial=$1 work=$2 title=$3 iterations=$4
    cp "$tutorial/system/fvSchemes" "$work/system/"
    sed 's/^\( *\)consistent yes;/\1consistent yes;\n\1residualControl\n\1{\n\1    p               1e-4;\n\1    U               1e-5;\n\1    "(k|epsilon)"   1e-5;\n\1}/' \
        "$tutorial/system/fvSolution" > "$work/system/fvSolution"
    grep -q residualControl "$work/system/fvSolution" || { echo "build.sh: fvSolution: no 'consistent yes;' to add residualControl to" >&2; exit 1; }
    cat > "$work/system/controlDict" <<DICT
/*--------------------------------*- C++ -*----------------------------------*\\
  $title
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
$(foam_flow_functions inlet outlet)
}
DICT
}

# The controlDict function objects that sum phi over two patches every step
# (postProcessing/<patch>Flow/0/surfaceFieldValue.dat): foam_flow_functions IN OUT
foam_flow_functions() {
    cat <<DICT
    $1Flow
    {
        type            surfaceFieldValue;
        libs            ("libfieldFunctionObjects.so");
        writeControl    timeStep;
        writeInterval   1;
        log             false;
        writeFields     false;
        regionType      patch;
        name            $1;
        operation       sum;
        fields          (phi);
    }
    $2Flow
    {
        \$$1Flow;
        name            $2;
    }
DICT
}

foam_check_mesh() {
    local script=$1
    grep -q "Mesh OK." log.checkMesh || { echo "$script: checkMesh failed:" >&2; grep -i -B2 -A2 "\*\*\*" log.checkMesh >&2; trap - EXIT; exit 1; }
    cells=$(awk '/^ *cells:/ {print $2; exit}' log.checkMesh)
    grep -E "^ *(points|faces|cells):|non-orthogonality Max|Max skewness|Max aspect ratio" log.checkMesh | sed 's/^ */   /'
    awk '/Checking patch topology/ {on = 1} on && /^ *(inlet|outlet|walls) / {print "   patch " $0} /Checking faceZone/ {on = 0}' log.checkMesh | sed 's/  */ /g'
}

foam_residuals() {
    local log=$1 f; shift
    if grep -q "reached convergence" "$log"; then
        grep "reached convergence" "$log" | sed 's/^/   /'
    else
        echo "   residualControl targets not met: stopped at the iteration count"
    fi
    echo "initial residuals (first solve of each iteration): first; last"
    for f in "$@"; do
        awk -v f="$f" '
            /^Time = / { seen = 0 }
            $0 ~ ("Solving for " f ",") && !seen {
                seen = 1; r = $0; sub(/.*Initial residual = /, "", r); sub(/,.*/, "", r); r += 0
                if (n++ == 0) first = r; last = r
            }
            END { printf "   %-8s %.2e; %.2e\n", f, first, last }' "$log"
    done
    echo "continuity (last): $(grep 'continuity errors' "$log" | tail -1 | sed 's/^ *//')"
}

foam_export() {
    local out=$1 final=$2 fields=$3 f; shift 3
    rm -rf "$out"
    mkdir -p "$out/constant/polyMesh" "$out/$final" "$out/system"
    for f in points faces owner neighbour boundary; do
        gzip -9 -n -c "constant/polyMesh/$f" > "$out/constant/polyMesh/$f.gz"
    done
    for f in $fields; do
        if [ -f "$final/$f" ]; then gzip -9 -n -c "$final/$f" > "$out/$final/$f.gz"; fi
    done
    cp constant/transportProperties constant/turbulenceProperties "$out/constant/"
    for f in "$@"; do cp "system/$f" "$out/system/"; done
    cp "$summary" "$out/summary.txt"
}
