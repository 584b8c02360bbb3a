#!/usr/bin/env bash
# The main job: builds hnn and reproduces the paper's Table 1 with charts into results/.
# Arguments go to `hnn reproduce` (e.g. --tasks spring,two-body --seeds 3). Safe to re-run.
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
out=${HNN_RESULTS:-results}
build/apps/hnn reproduce --out "$out" "$@"
# Figure 5: the energy bump of the pixel pendulum's HNN (seed 0), when that task ran.
for run in "$out/pixel-pendulum/hnn" "$out/pixel-pendulum/hnn/seed-0"; do
  if [[ -f $run/metrics.json ]]; then build/apps/hnn bump "$run"; fi
done
/usr/bin/python3 scripts/plot.py "$out"
/usr/bin/python3 scripts/plot_pixel.py "$out"
echo "reproduce.sh: table in $out/table1.md, charts in $out/*.png"
