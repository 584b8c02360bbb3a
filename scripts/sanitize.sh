#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (-DHNN_SANITIZE=ON),
# built in its own folder (build-asan) so that it never disturbs build/. -O2 keeps the suite fast
# (Eigen is inlined and vectorised; -O1 made training ~50x slower than Release); -g1 gives the
# reports file:line; asserts stay on (no NDEBUG). The libraries train at -O2 while the test files,
# which mostly set up and assert, build at -O1 (tests/CMakeLists.txt). UBSan leaves out its pointer
# checks, half of the build's time (CMakeLists.txt says why), and each test program runs whole in
# four shards, <module>.shard0..3 (tests/CMakeLists.txt). Built with clang, which compiles the
# instrumented build in 1,489 s of CPU where GCC took 2,108 (a 2-core Zen 3, 2026-11-27), while
# build/ (scripts/test.sh) stays GCC's: the pass checks our code, not one compiler's output.
# Any finding fails the test that triggers it. Safe to re-run. HNN_JOBS sets the parallelism
# (default: the CPU count).
# Usage: scripts/sanitize.sh [--only MODULE,...] [ctest arguments]
#   --only autodiff,nn   builds and runs only those test programs (tests/<module>/) and the
#                        libraries they link: what CI runs (.ci/run says why);
#   ctest arguments      e.g. -R reliability.
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${HNN_ASAN_BUILD_DIR:-build-asan}
targets=()
only=()
if [ "${1:-}" = --only ]; then
  IFS=, read -ra modules <<<"${2:?sanitize.sh: --only needs test modules, e.g. autodiff,nn}"
  shift 2
  for module in "${modules[@]}"; do
    if [ ! -d "tests/$module" ]; then
      echo "sanitize.sh: --only: no test module '$module' (no folder tests/$module)" >&2
      exit 2
    fi
    targets+=(--target "${module}_tests")
  done
  only=(-R "^($(IFS='|'; echo "${modules[*]}"))\\.")
fi
scripts/setup.sh clang libclang-rt-dev  # clang and its sanitizer runtimes
jobs=${HNN_JOBS:-$(nproc)}
start=$(date +%s)
# Third-party leaks (scripts/lsan.supp) are suppressed for every test program, including when
# ctest lists its tests (gtest_discover_tests).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$(pwd)/scripts/lsan.supp:print_suppressions=0}
generator=(-G Ninja)
[ ! -f "$build_dir/CMakeCache.txt" ] || generator=()
cmake -S . -B "$build_dir" "${generator[@]}" -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
  -DCMAKE_CXX_FLAGS_DEBUG="-O2 -g1" -DHNN_SANITIZE=ON -DHNN_BUILD_BENCH=OFF >/dev/null
cmake --build "$build_dir" -j "$jobs" "${targets[@]}"
built=$(date +%s)
# halt_on_error: the first report fails the test; leak checking stays on (ASan's default), and
# so does use-after-scope. Use-after-return detection stays off (the runtime's default): its fake
# stack frames misalign Eigen's 64-byte-aligned stack temporaries, and without UBSan's alignment
# check aligned AVX-512 loads of them fault (under GCC, 20 of the 24 test shards stopped with SEGV
# in Eigen).
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
# Twice as many tests as cores at once: an instrumented hnn program spends ~0.3 s of its ~0.4 s
# wall at exit in LeakSanitizer's scan, mostly waiting, and the reliability tests start hundreds.
ctest --test-dir "$build_dir" --output-on-failure -j "$((2 * jobs))" "${only[@]}" "$@"
echo "sanitize.sh: no findings (build $((built - start)) s, tests $(($(date +%s) - built)) s)"
