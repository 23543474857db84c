#!/usr/bin/env bash
# Installs, with apt-get, exactly the Debian packages mpmcd needs that are not yet installed.
# Usage: tools/install_deps.sh        (run as root, or with sudo available)
set -euo pipefail
packages=(
  build-essential cmake ninja-build git pkg-config
  libeigen3-dev libopenblas-openmp-dev libtomlplusplus-dev libcli11-dev libspdlog-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev libomp-dev libhdf5-dev hdf5-tools
  python3 python3-matplotlib python3-numpy python3-scipy python3-meshio
  libopenmpi-dev openmpi-bin libsuitesparse-dev
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages already installed"
  exit 0
fi
echo "install_deps: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
