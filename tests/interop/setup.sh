#!/usr/bin/env bash
# Create (or update) the Python virtualenv used by tests/interop/check.py.
#
# Usage: bash tests/interop/setup.sh      (from anywhere; the venv goes to <repo>/.venv-interop)
#
# Idempotent: an existing venv is reused, and pip only installs what is missing.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
venv="${SCG_INTEROP_VENV:-$repo/.venv-interop}"
python="${PYTHON:-python3}"

if [ ! -x "$venv/bin/python" ]; then
    echo "creating virtualenv $venv"
    "$python" -m venv "$venv"
fi

# Pinned: the versions the interop check was last verified with.
"$venv/bin/python" -m pip install --quiet \
    "rerun-sdk==0.36.3" \
    "mcap==1.6.0" \
    "foxglove-schemas-protobuf==0.4.0" \
    "protobuf==7.36.2" \
    "numpy==2.4.6" \
    "meshio==5.3.5"

"$venv/bin/python" - <<'PY'
import importlib.metadata as md
for name in ("rerun-sdk", "mcap", "foxglove-schemas-protobuf", "protobuf", "numpy", "meshio"):
    print(f"{name}=={md.version(name)}")
PY
echo "interop venv ready: $venv (run: $venv/bin/python tests/interop/check.py REC.rrd REC.mcap)"
