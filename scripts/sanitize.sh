#!/usr/bin/env bash
# Builds the core and dynamics test suites with AddressSanitizer + UndefinedBehaviorSanitizer
# (the asan-ubsan preset of CMakePresets.json, in build-asan/) and runs them, leaks detected.
# The whole suite (`cmake --build --preset asan-ubsan && ctest --preset asan-ubsan`) is a long
# job, not part of scripts/test.sh: the preset builds at -O2 -g1 with ASan's checks inlined
# (about 20 minutes on the 2-core machine, the Ceres-heavy translation units most of it) and its
# tests run with SPACETIME_TIME_SCALE=30, every solve's budget and every test's wait stretched
# thirtyfold, since an instrumented solve is about 7 times slower (the suite takes more than an
# hour on two cores; docs/validation.md).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --preset asan-ubsan > /dev/null
cmake --build build-asan -j2 --target core_tests dynamics_tests
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
build-asan/tests/core_tests
build-asan/tests/dynamics_tests
