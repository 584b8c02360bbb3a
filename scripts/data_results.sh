#!/usr/bin/env bash
# The data files of sweeps/data_results.yaml (docs/data_results.md, issue 17), which a spec
# cannot make: three Hamiltonians the paper lacks simulated by `hnn simulate`, copies of their
# files in other units (x100, x0.01), and the real pendulum's forward differences within a
# trial, all into results/data/ (the paths the spec names). Then:
#   build/apps/hnn sweep sweeps/data_results.yaml --out results/data/sweep
#   /usr/bin/python3 scripts/plot_study.py data_results results/data/sweep
# Usage: scripts/data_results.sh   (seconds)
source "$(dirname "$0")/help.sh"
set -euo pipefail
cd "$(dirname "$0")/.."
out=results/data
scripts/build.sh >/dev/null
hnn=$(pwd)/build/apps/hnn
mkdir -p "$out"

# name | H | coords | momenta | sampling box | energy band ("" for none). 50 trajectories of 6
# time units (40 points), noise on the states, exact dx/dt (simulate's derivative columns).
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
  for f in 100 0.01; do
    scaled "$file" "$f" >"$out/$name-x$f.csv"
  done
done

# The real pendulum's targets as the real-pendulum task makes them: forward differences within a
# trial, the trial's last row dropped.
awk 'BEGIN{print "trial,t,o,v,do,dv"} /^%/||NF<4{next}
     {if (n && $1==tr) printf "%s,%.17g,%.17g,%.17g,%.17g,%.17g\n", tr, t, o, v, ($3-o)/($2-t), ($4-v)/($2-t);
      tr=$1; t=$2; o=$3; v=$4; n=1}' data/lipson/real_pend_h_1.txt >"$out/real_pend_forward.csv"
echo "data_results.sh: the files of sweeps/data_results.yaml are in $out/" >&2
