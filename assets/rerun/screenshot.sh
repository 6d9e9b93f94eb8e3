#!/usr/bin/env bash
# Screenshot of the rerun viewer showing a recording with its stored blueprint, headless.
# Not part of .ci/run or the tests: it needs the viewer (`pip install rerun-sdk==0.36.3`) and
#   apt-get install -y xvfb mesa-vulkan-drivers x11-apps imagemagick
# Usage: assets/rerun/screenshot.sh RECORDING.rrd OUT.png [WAIT_SECONDS]
#
# The viewer draws with wgpu on lavapipe (Mesa's software Vulkan). Xvfb runs without the
# Composite extension: with it the viewer gets a 32-bit (transparent) window, which Mesa 22's
# software swapchain leaves black; GL (llvmpipe) fails at start ("Adapter does not support
# drawing to texture format R32Float").
# The viewer's own `--headless --screenshot-to FILE --window-size WxH` also works here, without
# X, but shoots at once: the start-up notices still cover the plots.
set -euo pipefail
rrd=${1:?recording .rrd}
out=${2:?output .png}
wait_s=${3:-20}
display=:${DISPLAY_NUMBER:-97}
size=${SIZE:-1600x1000}
viewer=$(python3 -c 'import os, rerun_cli; print(os.path.join(os.path.dirname(rerun_cli.__file__), "rerun"))' 2>/dev/null \
    || command -v rerun)
work=$(mktemp -d)
Xvfb "$display" -screen 0 "${size}x24" -extension Composite >"$work/xvfb.log" 2>&1 &
xvfb=$!
viewer_pid=
cleanup() {
    [ -n "$viewer_pid" ] && kill "$viewer_pid" 2>/dev/null || true
    kill "$xvfb" 2>/dev/null || true
    rm -rf "$work"
}
trap cleanup EXIT
sleep 2
# A fresh state directory: no layout or blueprint saved by an earlier session is loaded, so the
# picture shows the blueprint stored in the recording.
mkdir -p "$work/data" "$work/runtime" && chmod 700 "$work/runtime"
DISPLAY=$display XDG_DATA_HOME=$work/data XDG_RUNTIME_DIR=$work/runtime WGPU_BACKEND=vulkan \
    "$viewer" --port 0 "$rrd" >"$work/viewer.log" 2>&1 &
viewer_pid=$!
sleep "$wait_s"
DISPLAY=$display xwd -root -silent | convert xwd:- -strip -colors 256 "PNG8:$out"
echo "wrote $out ($(du -k "$out" | cut -f1) KB)"
