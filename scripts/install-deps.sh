#!/usr/bin/env bash
# Installs the Debian 12 packages Spacetime needs, only those that are missing, and the Khronos
# glTF Validator (npm) the tests check exported glTF with, into .cache/ (not committed). clang is
# for the scene loader's fuzzer (scripts/fuzz.sh, and a 60 s run in the tests); IPOPT
# (coinor-libipopt-dev) for the interior-point method (`--method ipopt`); Pinocchio (pip, into
# .cache/python) for a test. `install-deps.sh --with-blender` also installs Blender's Python
# module (pip bpy, about 1 GB, into .cache/bpy) for an optional BVH import test.
set -euo pipefail
packages=(cmake ninja-build g++ clang ccache pkg-config
          libeigen3-dev libceres-dev nlohmann-json3-dev coinor-libipopt-dev
          libgtest-dev libbenchmark-dev libmujoco-dev libtinygltf-dev
          qt6-base-dev libqt6opengl6-dev qt6-charts-dev libglm-dev libgl-dev
          xvfb xauth python3-pip)
missing=()
# Node.js with npm for the validator (Debian's nodejs and npm unless a Node.js with npm is there).
command -v npm >/dev/null 2>&1 || packages+=(nodejs npm)
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi

validator_version=2.0.0-dev.3.10
validator_dir="$(cd "$(dirname "$0")/.." && pwd)/.cache/gltf-validator"
if ! grep -qs "\"version\": \"$validator_version\"" "$validator_dir/node_modules/gltf-validator/package.json"; then
  echo "installing the Khronos glTF Validator $validator_version (npm) into $validator_dir"
  mkdir -p "$validator_dir"
  # Only the tests need it: without the npm registry the editor still builds and runs, and the
  # validator test says what is missing.
  npm install --silent --no-save --no-audit --no-fund --prefix "$validator_dir" "gltf-validator@$validator_version" ||
    echo "warning: could not install the glTF Validator; GltfValidator.AcceptsEveryShippedScene will fail" >&2
fi

# Pinocchio (pip `pin`) for the test that re-checks solved torques on the Z-up URDF with its
# default settings (tests/interop/pinocchio_check.py); into .cache/python, not the system.
python_dir="$(cd "$(dirname "$0")/.." && pwd)/.cache/python"
pin_version=4.1.0
if ! python3 -c "import site; site.addsitedir('$python_dir'); import pinocchio; assert pinocchio.__version__ == '$pin_version'" 2>/dev/null; then
  echo "installing Pinocchio $pin_version (pip pin) into $python_dir"
  rm -rf "$python_dir"
  python3 -m pip install --quiet --disable-pip-version-check --target "$python_dir" "pin==$pin_version" 2>&1 | grep -v "Running pip as the 'root' user" ||
    true
  python3 -c "import site; site.addsitedir('$python_dir'); import pinocchio" 2>/dev/null ||
    echo "warning: could not install Pinocchio; pinocchio_z_up_urdf will fail" >&2
fi

# Optional (--with-blender): Blender as a Python module (pip bpy, about 1 GB) for the test that
# imports a solved BVH with Blender's default settings (tests/interop/blender_bvh_check.py; the
# test exists when .cache/bpy does).
if [ "${1:-}" = "--with-blender" ]; then
  bpy_dir="$(cd "$(dirname "$0")/.." && pwd)/.cache/bpy"
  if ! python3 -c "import site; site.addsitedir('$bpy_dir'); import bpy" 2>/dev/null; then
    echo "installing Blender 5.0.1 (pip bpy) into $bpy_dir"
    python3 -m pip install --quiet --disable-pip-version-check --target "$bpy_dir" "bpy==5.0.1" 2>&1 |
      grep -v "Running pip as the 'root' user" || true
  fi
fi
