#!/usr/bin/env bash
# Quick start: install what is missing, build (Release), and open the editor on the Luxo jump,
# which solves as it opens. Without a display (no $DISPLAY or $WAYLAND_DISPLAY) it solves the
# Luxo jump headless instead, writing summary.json, motion.json, motion.glb, luxo.urdf and
# luxo.bvh to out/luxo_jump/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2 --target spacetime spacetime-cli
if [ -n "${DISPLAY:-}${WAYLAND_DISPLAY:-}" ]; then
  exec ./build/app/spacetime resources/scenes/luxo_jump.json
fi
echo "no display: solving headless"
status=0
./build/app/spacetime-cli solve resources/scenes/luxo_jump.json --out out/luxo_jump "$@" || status=$?
# Exit status 3 means the solve stopped without converging, 4 that it converged but failed a
# validity check; the outputs are written either way (summary.json says why). Anything else
# non-zero is an error.
if [ "$status" -ne 0 ] && [ "$status" -ne 3 ] && [ "$status" -ne 4 ]; then exit "$status"; fi
[ "$status" -eq 3 ] && echo "warning: the solve did not converge; see out/luxo_jump/summary.json"
[ "$status" -eq 4 ] && echo "warning: the motion failed a validity check; see out/luxo_jump/summary.json"
echo "outputs in out/luxo_jump/"
