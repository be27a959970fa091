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
