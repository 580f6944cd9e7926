#!/usr/bin/env bash
# The main job: installs what is missing, builds, runs the paper's two scenarios and plots them.
# Results (plan.sto, simulation.sto, summary.json, PNG figures) go to results/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/install_deps.sh"
"$root/scripts/build.sh"
results="$root/results"
mkdir -p "$results"
echo "== open loop: [0, 10] deg -> straight up in 3 s (reserves 10 N)"
"$root/build/bin/arm_open_loop" --out "$results/open_loop"
echo "== receding horizon: [20, 20] deg -> [80, 80] deg, 2 s (reserves 1 N)"
"$root/build/bin/arm_receding_horizon" --out "$results/receding_horizon"
echo "== figures"
# Debian's interpreter, which has python3-matplotlib (a python3 earlier on PATH may not).
python=/usr/bin/python3
[[ -x $python ]] || python=python3
"$python" "$root/scripts/plot_results.py" "$results"
echo "demo: results in $results"
