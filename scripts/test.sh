#!/usr/bin/env bash
# The test command: installs what is missing, builds, runs the whole test suite, then installs
# the package and builds the examples/ projects against it. Safe to re-run.
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
scripts/build.sh
# Twice as many tests as cores: many wait on a child process (the hnn program, python, Dask's
# workers) for part of their time; the suite took 133 s at -j 4 against 174 s at -j 2 (2 cores).
ctest --test-dir build --output-on-failure -j "$((2 * $(nproc)))"

# The exported package: examples/consumer links hnn::autodiff alone through find_package(hnn).
rm -rf build/install build/consumer build/henon_heiles
cmake --install build --prefix "$root/build/install" >/dev/null
cmake -S examples/consumer -B build/consumer -DCMAKE_PREFIX_PATH="$root/build/install" >/dev/null
cmake --build build/consumer -j "$(nproc)" >/dev/null
build/consumer/hessian_demo
# examples/henon_heiles: a system of one's own (Hénon–Heiles written with the engine's ops, through
# hnn::physics_autodiff) learned through hnn::tasks; fails unless the HNN conserves energy better.
cmake -S examples/henon_heiles -B build/henon_heiles -DCMAKE_PREFIX_PATH="$root/build/install" \
  >/dev/null
cmake --build build/henon_heiles -j "$(nproc)" >/dev/null
build/henon_heiles/henon_heiles
# The Python package as installed (apps/python/CMakeLists.txt; README.md "From Python").
for site in build/install/lib/python3*/dist-packages; do
  [ ! -d "$site/hnn" ] || PYTHONPATH="$root/$site" /usr/bin/python3 -c \
    'import hnn; hnn.HNN(2, hidden=(4,)).vector_field([[0.0, 1.0]])'
done
echo "test.sh: all tests passed"
