#!/usr/bin/env bash
# Fuzzes the scene loader for SECONDS (default 600) with libFuzzer under AddressSanitizer and
# UndefinedBehaviorSanitizer, seeded with every shipped and test scene, under a 4 GB memory
# limit; a crash, a hang (> 10 s on one input) or running out of memory fails it, leaving the
# input in build-fuzz/. Needs clang (scripts/install-deps.sh installs it).
#   scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
out=build-fuzz
mkdir -p "$out/corpus"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is missing (scripts/install-deps.sh installs it)" >&2; exit 2; }
binary="$out/scene_loader_fuzz"
sources=(core/src/*.cpp core/src/expr/*.cpp tests/fuzz/scene_loader_fuzz.cpp)
if [ ! -x "$binary" ] || [ -n "$(find "${sources[@]}" core/include -newer "$binary" | head -1)" ]; then
  echo "building $binary"
  # shellcheck disable=SC2046
  clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -Icore/include $(pkg-config --cflags eigen3) "${sources[@]}" -o "$binary"
fi
cp resources/scenes/*.json tests/scenes/*.json tests/scenes/ladder/*.json "$out/corpus/" 2>/dev/null || true
"$binary" "$out/corpus" -dict=tests/fuzz/scene.dict -max_total_time="$seconds" -timeout=10 \
  -rss_limit_mb=4096 -max_len=65536 -artifact_prefix="$out/" -print_final_stats=1 2>&1 | tail -25
