#!/usr/bin/env bash
# The dissipative HNN beside the peers' published numbers (issue 18, part 1): the D-HNN paper's
# damped spring and its real-pendulum protocol (80/20 in time, central differences, width 256,
# batch 128, 5000 steps at 5e-3), each model on 3 seeds; 15 energy rollouts, as when
# docs/families.md's figures were measured (the default is now 100). Writes OUT/results.md.
# Usage: scripts/dhnn_results.sh [OUT]   (default results/dhnn; about 10 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/dhnn}
scripts/build.sh >/dev/null
hnn=$(pwd)/build/apps/hnn
seeds=${HNN_DHNN_SEEDS:-3}
mkdir -p "$out"
for seed in $(seq 0 $((seeds - 1))); do
  for model in dhnn baseline hnn; do
    "$hnn" train damped-spring --model "$model" --seed "$seed" --quiet \
      --out "$out/runs/damped-spring/$model/seed-$seed" >/dev/null
    "$hnn" train data --data data/lipson/real_pend_h_1.txt --model "$model" --seed "$seed" \
      --hidden 256 256 --batch 128 --steps 5000 --lr 5e-3 \
      --hamiltonian "2.4*(1 - cos(o)) + v^2" --settings '{"energy_t_end": 20, "rollouts": 15}' \
      --quiet \
      --out "$out/runs/real-pendulum/$model/seed-$seed" >/dev/null
  done
  echo "dhnn_results.sh: seed $seed done" >&2
done
/usr/bin/python3 - "$out" >"$out/results.md" <<'PY'
import json, math, pathlib, sys
out = pathlib.Path(sys.argv[1])
peers = {  # the D-HNN paper's analysis notebooks (one seed each)
    ("damped-spring", "dhnn"): {"test_loss": 5.75e-5, "dhnn_paper_state_mse": 3.6e-6},
    ("damped-spring", "baseline"): {"test_loss": 9.86e-5, "dhnn_paper_state_mse": 6.0e-6},
    ("damped-spring", "hnn"): {"test_loss": 0.626, "dhnn_paper_state_mse": 0.29},
    ("real-pendulum", "dhnn"): {"test_loss": 9.46e-4, "held_out_energy_mse": 1.068e-3},
    ("real-pendulum", "baseline"): {"test_loss": 1.11e-3, "held_out_energy_mse": 1.167e-3},
    ("real-pendulum", "hnn"): {"test_loss": 1.40e-3, "held_out_energy_mse": 1.018e-2},
}
keys = {"damped-spring": ["test_loss", "dhnn_paper_state_mse", "dissipation_share",
                          "train_seconds"],
        "real-pendulum": ["test_loss", "held_out_energy_mse", "energy_mse",
                          "valid_prediction_time", "dissipation_share", "train_seconds"]}
def stats(v):
    v = [x for x in v if x is not None]
    if not v: return math.nan, math.nan
    m = sum(v) / len(v)
    se = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1) / len(v)) if len(v) > 1 else math.nan
    return m, se
for task, names in keys.items():
    print(f"### {task}\n")
    print("| model | " + " | ".join(names) + " |")
    print("| --- | " + " | ".join("---" for _ in names) + " |")
    for model in ("dhnn", "baseline", "hnn"):
        runs = [json.loads((d / "metrics.json").read_text())
                for d in sorted((out / "runs" / task / model).glob("seed-*"))]
        cells = []
        for k in names:
            m, se = stats([r.get(k) for r in runs])
            cell = f"{m:.3g} ± {se:.1g}" if math.isfinite(se) else f"{m:.3g}"
            peer = peers.get((task, model), {}).get(k)
            cells.append(cell + (f" (peer {peer:.3g})" if peer is not None else ""))
        print(f"| {model} ({len(runs)} seeds) | " + " | ".join(cells) + " |")
    print()
PY
cat "$out/results.md"
