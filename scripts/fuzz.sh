#!/usr/bin/env bash
# Fuzzes the scene loader for SECONDS (default 600) with libFuzzer under AddressSanitizer and
# UndefinedBehaviorSanitizer, seeded with every shipped and test scene, under a 4 GB memory
# limit; a crash, a hang (> 10 s on one input) or running out of memory fails it, leaving the
# input in build-fuzz/. Needs clang (scripts/install-deps.sh installs it).
#   scripts/fuzz.sh [SECONDS] [SEED]
# Without SEED the corpus in build-fuzz/corpus grows from run to run. With SEED (the tests use
# 1) the run starts from the seeds alone with that random seed: the same inputs in the same order
# on every machine, so a run that passed here passes in CI.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-600}"
seed="${2:-}"
out=build-fuzz
mkdir -p "$out"
command -v clang++ >/dev/null || { echo "fuzz.sh: clang++ is missing (scripts/install-deps.sh installs it)" >&2; exit 2; }
binary="$out/scene_loader_fuzz"
sources=(core/src/*.cpp core/src/expr/*.cpp tests/fuzz/scene_loader_fuzz.cpp)
if [ ! -x "$binary" ] || [ -n "$(find "${sources[@]}" core/include -newer "$binary" | head -1)" ]; then
  echo "building $binary"
  # shellcheck disable=SC2046
  clang++ -std=c++20 -O1 -g -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined \
    -Icore/include $(pkg-config --cflags eigen3) "${sources[@]}" -o "$binary.new-$$"
  mv "$binary.new-$$" "$binary"
fi
options=(-dict=tests/fuzz/scene.dict -max_total_time="$seconds" -timeout=10 -rss_limit_mb=4096
         -max_len=65536 -artifact_prefix="$out/" -print_final_stats=1)
if [ -n "$seed" ]; then
  corpus="$(mktemp -d)"
  trap 'rm -rf "$corpus"' EXIT
  options+=(-seed="$seed")
else
  corpus="$out/corpus"
  mkdir -p "$corpus"
fi
cp resources/scenes/*.json tests/scenes/*.json tests/scenes/ladder/*.json "$corpus/"
"$binary" "$corpus" "${options[@]}" 2>&1 | tail -25
