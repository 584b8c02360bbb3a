#!/usr/bin/env bash
# Soak test (a script, not CI): trains the spring HNN for STEPS steps (default 100000) with a
# checkpoint every INTERVAL steps (default 1000) and samples the process at each checkpoint:
# resident memory now and at its peak (VmRSS, VmHWM from /proc) and the time per step over the
# last interval (from the checkpoint's training seconds). Prints one row per sample, then the
# peak RSS at the first sample (1k steps) and at the end, and the step time of the first and the
# last tenth. Memory must stay flat and the step time must not creep.
#   scripts/soak.sh [extra hnn train options, e.g. --hidden 64 64]
# Environment: STEPS, INTERVAL, OUT (run folder, default build/soak), HNN (the program).
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
steps=${STEPS:-100000}
interval=${INTERVAL:-1000}
out=${OUT:-build/soak}
hnn=${HNN:-build/apps/hnn}
[ -x "$hnn" ] || scripts/build.sh >/dev/null
rm -rf "$out"
mkdir -p "$(dirname "$out")"
log="$out.samples.csv"

"$hnn" train spring --steps "$steps" --checkpoint-every "$interval" --quiet --out "$out" "$@" \
  >"$out.stdout" 2>"$out.stderr" &
pid=$!
trap 'kill $pid 2>/dev/null || true' EXIT

state="$out/checkpoint/state.json"
field() { grep -o "\"$1\":[0-9.eE+-]*" "$state" 2>/dev/null | head -1 | cut -d: -f2; }
kb() { sed -n "s/^$1:[[:space:]]*\([0-9]*\) kB/\1/p" "/proc/$pid/status" 2>/dev/null; }

echo "step,rss_kb,peak_rss_kb,ms_per_step" >"$log"
printf "%8s %10s %10s %12s\n" step "RSS MB" "peak MB" "ms/step"
last_step=0
last_seconds=0
while kill -0 "$pid" 2>/dev/null; do
  step=$(field step || true)
  if [ -n "$step" ] && [ "$step" != "$last_step" ]; then
    seconds=$(field seconds)
    rss=$(kb VmRSS)
    hwm=$(kb VmHWM)
    [ -n "$rss" ] || break
    ms=$(awk -v s="$seconds" -v l="$last_seconds" -v a="$step" -v b="$last_step" \
      'BEGIN { printf "%.4f", 1000 * (s - l) / (a - b) }')
    echo "$step,$rss,$hwm,$ms" >>"$log"
    printf "%8d %10.1f %10.1f %12s\n" "$step" "$(echo "$rss / 1024" | bc -l)" \
      "$(echo "$hwm / 1024" | bc -l)" "$ms"
    last_step=$step
    last_seconds=$seconds
  fi
  sleep 0.05
done
wait $pid || { echo "soak.sh: training failed:"; cat "$out.stderr"; exit 1; }
trap - EXIT

# Summary: peak RSS at the first and last samples; mean step time of the first and last tenth.
awk -F, 'NR > 1 { n++; step[n] = $1; hwm[n] = $3; ms[n] = $4 }
  END {
    tenth = int(n / 10); if (tenth < 1) tenth = 1
    for (i = 1; i <= tenth; i++) first += ms[i]
    for (i = n - tenth + 1; i <= n; i++) last += ms[i]
    printf "soak.sh: peak RSS %.1f MB at step %d, %.1f MB at step %d (%+.2f%%)\n",
      hwm[1] / 1024, step[1], hwm[n] / 1024, step[n], 100 * (hwm[n] - hwm[1]) / hwm[1]
    printf "soak.sh: %.4f ms/step over the first tenth, %.4f over the last (%+.1f%%)\n",
      first / tenth, last / tenth, 100 * (last - first) / first
  }' "$log"
echo "soak.sh: samples in $log; train_seconds $(grep -o '"train_seconds": [0-9.]*' \
  "$out/metrics.json" | cut -d' ' -f2)"
