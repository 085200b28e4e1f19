#!/usr/bin/env bash
# Quick start: install what is missing, build (Release), and solve the Luxo jump headless,
# writing summary.json, motion.json and luxo.urdf into out/luxo_jump/.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2 --target spacetime-cli
./build/app/spacetime-cli solve resources/scenes/luxo_jump.json --out out/luxo_jump "$@"
echo "outputs in out/luxo_jump/"
