#!/usr/bin/env bash
# Configures and builds hnn (Release, this CPU's vector extensions) in build/. Safe to re-run.
# Extra arguments go to cmake's configure step, e.g. -DHNN_NATIVE=OFF.
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
build_dir=${HNN_BUILD_DIR:-build}
# Ninja (a build folder configured before with another generator keeps it).
generator=(-G Ninja)
[ ! -f "$build_dir/CMakeCache.txt" ] || generator=()
cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
