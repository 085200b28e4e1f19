#!/usr/bin/env bash
# Installs the Debian 12 packages Spacetime needs, only those that are missing.
set -euo pipefail
packages=(cmake ninja-build g++ ccache pkg-config
          libeigen3-dev libceres-dev nlohmann-json3-dev
          libgtest-dev libbenchmark-dev libmujoco-dev
          qt6-base-dev libqt6opengl6-dev qt6-charts-dev libglm-dev libgl-dev
          xvfb xauth)
missing=()
for p in "${packages[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing: ${missing[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi
