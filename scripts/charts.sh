#!/usr/bin/env bash
# The speed-against-accuracy charts of docs/speed_accuracy.md: builds the two programs of
# bench/accuracy/ in build-charts/, runs them (CSV files) and draws PNG + SVG into docs/charts/.
# Usage: scripts/charts.sh [--quick]   (--quick: a smoke run with coarse sweeps, minutes -> seconds)
# Environment: HNN_CHARTS_OUT (default docs/charts), HNN_CHARTS_BUILD (default build-charts),
# HNN_CHARTS_THREADS (engine threads, default 1: steadier timings on a shared machine).
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
out=${HNN_CHARTS_OUT:-docs/charts}
build=${HNN_CHARTS_BUILD:-build-charts}
threads=${HNN_CHARTS_THREADS:-1}
quick=()
if [[ "${1:-}" == "--quick" ]]; then quick=(--quick); fi

start=$(date +%s)
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
nice cmake --build "$build" -j 2 --target fd_vs_autodiff work_precision
mkdir -p "$out"
echo "charts.sh: autodiff vs finite differences"
nice "$build/bench/accuracy/fd_vs_autodiff" --out "$out" --threads "$threads" "${quick[@]}"
echo "charts.sh: integrators (work-precision and energy drift)"
nice "$build/bench/accuracy/work_precision" --out "$out" --threads "$threads" "${quick[@]}"
/usr/bin/python3 scripts/plot_speed_accuracy.py "$out"
echo "charts.sh: charts and CSV files in $out/ ($(( $(date +%s) - start )) s)"
