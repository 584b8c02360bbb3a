#!/usr/bin/env bash
# Installs the Debian packages hnn needs, only those missing, and any packages named as arguments
# (scripts/sanitize.sh and fuzz.sh add clang). Safe to re-run.
source "$(dirname "$0")/help.sh"
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  libeigen3-dev libfmt-dev libcli11-dev nlohmann-json3-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libgif-dev libpng-dev libopenblas-pthread-dev libopenblas0-openmp libxtensor-dev libzip-dev libginac-dev libyaml-cpp-dev
  libssl-dev
  python3-matplotlib python3-numpy python3-distributed
  pybind11-dev python3-dev python3-pytest
  "$@"
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}"
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
