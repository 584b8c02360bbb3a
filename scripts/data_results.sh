#!/usr/bin/env bash
# The results the data task must hold (issue 17), measured from scratch: three Hamiltonians the
# paper lacks simulated by `hnn simulate`, each learned by an HNN and a baseline through
# `hnn train data`, and copies of their files in other units (x100, x0.01); and the shipped real
# pendulum through the data task beside the real-pendulum task. Writes OUT/results.md and
# Figure 2 of each system's seed-0 pair into OUT/charts/NAME/.
# Usage: scripts/data_results.sh [OUT]   (default results/data; about 15 minutes on 2 cores)
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/data}
scripts/build.sh >/dev/null
hnn=$(pwd)/build/apps/hnn
mkdir -p "$out"
seeds=${HNN_DATA_SEEDS:-3}

# name | H | coords | momenta | sampling box | energy band ("" for none). 50 trajectories of 6
# time units (40 points), noise on the states, exact dx/dt (--derivatives: simulate's columns);
# the energy MSE along 20 time units from the test states, as the paper's rollouts.
systems=(
  "nonseparable|(q^2 + 1)*(p^2 + 1)/2|q|p|q=-1.5:1.5,p=-1.5:1.5|"
  "henon-heiles|(px^2 + py^2)/2 + (x^2 + y^2)/2 + x^2*y - y^3/3|x,y|px,py|x=-0.5:0.5,y=-0.5:0.5,px=-0.5:0.5,py=-0.5:0.5|0.02:0.12"
  "double-well|p^2/2 + q^4/4 - q^2/2|q|p|q=-1.8:1.8,p=-1:1|"
)

# A copy of a simulated CSV with every state and derivative column multiplied by f.
scaled() { awk -F, -v f="$2" 'BEGIN{OFS=","; CONVFMT="%.17g"} NR==1{print;next} {for(i=3;i<=NF;i++) $i=$i*f; print}' "$1"; }

for system in "${systems[@]}"; do
  IFS='|' read -r name h coords momenta box band <<<"$system"
  file="$out/$name.csv"
  energy=(); [[ -n "$band" ]] && energy=(--energy "$band")
  "$hnn" simulate --hamiltonian "$h" --coords "$coords" --momenta "$momenta" --trajectories 50 \
    --t-end 6 --points 40 --noise 0.005 --sample "$box" "${energy[@]}" --seed 1 --out "$file" >&2
  derivatives=$(echo "$coords,$momenta" | sed 's|\([^,]*\)|d\1/dt|g')
  common=(--coords "$coords" --momenta "$momenta" --derivatives "$derivatives")
  for seed in $(seq 0 $((seeds - 1))); do
    for model in hnn baseline; do
      "$hnn" train data --data "$file" "${common[@]}" --hamiltonian "$h" \
        --settings '{"energy_t_end": 20, "rollouts": 15}' --model "$model" --seed "$seed" --quiet \
        --out "$out/runs/$name/$model/seed-$seed" >/dev/null
    done
  done
  for f in 100 0.01; do
    scaled "$file" "$f" >"$out/$name-x$f.csv"
    "$hnn" train data --data "$out/$name-x$f.csv" "${common[@]}" --quiet \
      --out "$out/runs/$name/hnn-x$f" >/dev/null
  done
  echo "data_results.sh: $name done" >&2
done

# The real pendulum: the real-pendulum task, and the data task on the same targets (forward
# differences within a trial, the trial's last row dropped: the task's own), split and energy
# metric as the task's (the last 20% in time; 15 rollouts of 20 s under H = 2.4(1 - cos q) + p^2).
# 15 rollouts throughout (the default is 100): docs/data_results.md's figures were measured so.
awk 'BEGIN{print "trial,t,o,v,do,dv"} /^%/||NF<4{next}
     {if (n && $1==tr) printf "%s,%.17g,%.17g,%.17g,%.17g,%.17g\n", tr, t, o, v, ($3-o)/($2-t), ($4-v)/($2-t);
      tr=$1; t=$2; o=$3; v=$4; n=1}' data/lipson/real_pend_h_1.txt >"$out/real_pend_forward.csv"
for seed in $(seq 0 $((seeds - 1))); do
  for model in hnn baseline; do
    "$hnn" train real-pendulum --model "$model" --seed "$seed" --settings '{"rollouts": 15}' --quiet \
      --out "$out/runs/real-pendulum/$model/seed-$seed" >/dev/null
    "$hnn" train data --data "$out/real_pend_forward.csv" --coords o --velocities v \
      --derivatives do,dv --split time --hamiltonian "2.4*(1 - cos(o)) + v^2" \
      --settings '{"energy_t_end": 20, "gap_factor": 0, "rollouts": 15}' --model "$model" --seed "$seed" --quiet \
      --out "$out/runs/real-pendulum-data/$model/seed-$seed" >/dev/null
    "$hnn" train data --data data/lipson/real_pend_h_1.txt --hamiltonian "2.4*(1 - cos(o)) + v^2" \
      --settings '{"energy_t_end": 20, "rollouts": 15}' --model "$model" --seed "$seed" --quiet \
      --out "$out/runs/real-pendulum-central/$model/seed-$seed" >/dev/null
  done
done
for name in nonseparable henon-heiles double-well real-pendulum-central; do
  /usr/bin/python3 scripts/plot.py --runs "$out/runs/$name/hnn/seed-0" \
    "$out/runs/$name/baseline/seed-0" --out "$out/charts/$name" >/dev/null
done
/usr/bin/python3 scripts/data_results.py "$out" >"$out/results.md"
cat "$out/results.md"
