#!/usr/bin/env bash
# Installs every Debian 12 package hovs needs to build, test and run. Idempotent.
# Usage: scripts/setup.sh   (as root, or with sudo available)
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git ca-certificates python3
  libeigen3-dev libnlopt-cxx-dev libceres-dev
  libembree-dev libtbb-dev
  libopenimageio-dev openimageio-tools libopenexr-dev libpng-dev libjpeg-dev
  libopencv-dev libopencv-contrib-dev
  libvtk9-dev mpi-default-dev xvfb xauth
  libaravis-dev aravis-tools libusb-1.0-0-dev iproute2 util-linux
  libcli11-dev nlohmann-json3-dev libyaml-cpp-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  clang clang-format-14 libfuzzer-14-dev libclang-rt-14-dev
  slurm-wlm munge
  cyclonedds-dev cyclonedds-tools
  python3-dev pybind11-dev python3-pybind11 python3-pytest python3-numpy python3-opencv python3-open3d
)

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${#missing[@]} packages: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
