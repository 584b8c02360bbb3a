#!/usr/bin/env bash
# Fuzzes the readers of untrusted files with libFuzzer (clang, AddressSanitizer + UBSan): the
# Lipson data loader, the parameter-file reader, the training checkpoint's state.json and the
# measured-data table readers (CSV, .npy, .npz, Lipson text).
# Each harness runs for FUZZ_SECONDS (default 60) from its corpus, fuzz/corpus/<name>/, plus the
# inputs earlier runs found (build-fuzz/fuzz-work/<name>/). For the two file formats, inputs that
# reach new code are merged back into fuzz/corpus/<name>/ (train_state's would be a thousand
# variations of JSON syntax: they stay in the work folder). A crasher is copied to
# fuzz/regressions/<name>/ (both are replayed by tests/reliability/fuzz_corpus_test.cpp) and
# makes the script fail. Usage: scripts/fuzz.sh [name...]   (names: lipson params train_state
# table)
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${FUZZ_SECONDS:-60}
build_dir=${HNN_FUZZ_BUILD_DIR:-build-fuzz}
jobs=${HNN_JOBS:-$(nproc)}
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(lipson params train_state table)
scripts/setup.sh clang libclang-rt-dev  # clang and its libFuzzer runtime

CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHNN_FUZZ=ON \
  -DHNN_BUILD_TESTS=OFF -DHNN_BUILD_BENCH=OFF -DHNN_BUILD_APPS=OFF >/dev/null
targets=()
for name in "${names[@]}"; do targets+=("${name}_fuzz"); done
cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}"

# Third-party leaks (scripts/lsan.supp: GiNaC's CLN at exit) are not findings.
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$(pwd)/scripts/lsan.supp:print_suppressions=0}
status=0
for name in "${names[@]}"; do
  fuzzer="$build_dir/fuzz/${name}_fuzz"
  work="$build_dir/fuzz-work/$name"
  artifacts="$build_dir/fuzz-artifacts/$name"
  log="$build_dir/fuzz-$name.log"
  mkdir -p "$work" "$artifacts" "fuzz/corpus/$name"
  # New inputs go to the first folder (work); fuzz/corpus/<name> only seeds.
  if ! "$fuzzer" -max_total_time="$seconds" -max_len=8192 -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="$artifacts/" "$work" "fuzz/corpus/$name" \
      >"$log" 2>&1; then
    status=1
    mkdir -p "fuzz/regressions/$name"
    cp "$artifacts"/* "fuzz/regressions/$name/" 2>/dev/null || true
    echo "fuzz.sh: $name FOUND A CRASH; see $log; inputs copied to fuzz/regressions/$name/"
    grep -m1 -E "ERROR|SUMMARY|invariant broken|runtime error" "$log" || true
  fi
  before=$(find "fuzz/corpus/$name" -type f | wc -l)
  if [ "$name" != train_state ]; then
    "$fuzzer" -merge=1 "fuzz/corpus/$name" "$work" >>"$log" 2>&1 || true
  fi
  after=$(find "fuzz/corpus/$name" -type f | wc -l)
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1)
  echo "fuzz.sh: $name: ${runs:-?} executions in ${seconds} s, ${cov:-cov: ?}, corpus $before -> $after"
done
exit $status
