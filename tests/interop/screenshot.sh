#!/usr/bin/env bash
# Screenshot of a recording in the real Rerun viewer, headless (not run by CI).
#
# Usage: bash tests/interop/screenshot.sh REC.rrd OUT.png [WIDTHxHEIGHT]
#
# Needs the interop venv (tests/interop/setup.sh: rerun-sdk==0.36.3), a Vulkan driver
# (software rendering works: Debian's `mesa-vulkan-drivers`, llvmpipe) and ImageMagick's
# `convert`. The viewer renders at twice the logical size (3200x1800 by default); the
# PNG is downscaled to 1280 px wide and reduced to 128 colours (≈ 250 KB, for the README).
#
#   bash tests/interop/screenshot.sh recordings/vortex.rrd docs/img/vortex.png
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
venv="${SCG_INTEROP_VENV:-$repo/.venv-interop}"
rrd="$1"
out="$2"
size="${3:-1600x900}"
raw="$(mktemp --suffix=.png)"
trap 'rm -f "$raw"' EXIT

# RUST_LOG=error keeps the viewer's log notifications (e.g. "software rasterizer") out of
# the picture.
RUST_LOG=error "$venv/bin/rerun" --headless --window-size "$size" --screenshot-to "$raw" "$rrd"
convert "$raw" -resize 1280x -colors 128 "PNG8:$out"
echo "wrote $out ($(du -k "$out" | cut -f1) KiB)"
