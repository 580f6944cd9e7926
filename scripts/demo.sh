#!/usr/bin/env bash
# The main job: installs what is missing, builds, runs the paper's two scenarios and the shipped
# OpenSim models' (a seated knee extension, 13 muscles; a leg swing, 40 muscles) and plots them.
# Results (plan.sto, simulation.sto, summary.json, PNG figures, GIF animations, OpenSim motion
# files, the strength study's tables) go to results/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/install_deps.sh"
"$root/scripts/build.sh"
results="$root/results"
mkdir -p "$results"
echo "== open loop, the paper's quartic: [0, 10] deg -> straight up in 3 s (reserves 10 N)"
"$root/build/bin/arm_open_loop" --paper --out "$results/open_loop"
echo "== open loop, the default plan (quintic B-splines on 48 spans)"
"$root/build/bin/arm_open_loop" --out "$results/open_loop_default"
echo "== receding horizon: [20, 20] deg -> [80, 80] deg, 2 s (reserves 1 N)"
"$root/build/bin/arm_receding_horizon" --paper --out "$results/receding_horizon"
# The models made from OpenSim's example by opensim_to_model, each in its own scenarios.
models="$root/build/share/flatsos/models"
echo "== seated knee extension (13 muscles, hip held at 60 deg): open loop 90 -> 30 deg in 1 s (10 N)"
"$root/build/bin/arm_open_loop" --model "$models/seated_knee_r.json" --out "$results/seated_knee_r/open_loop"
echo "== seated knee extension: receding horizon 90 -> 20 deg, 1.5 s (1 N)"
"$root/build/bin/arm_receding_horizon" --model "$models/seated_knee_r.json" --out "$results/seated_knee_r/receding_horizon"
echo "== leg swing (hip, knee, ankle; 40 muscles): open loop from hanging to [40, 60, 10] deg in 1 s (10 N)"
"$root/build/bin/arm_open_loop" --model "$models/sagittal_leg_r.json" --out "$results/sagittal_leg_r/open_loop"
echo "== leg swing: receding horizon to [40, 60, 10] deg, 1.5 s (1 N)"
"$root/build/bin/arm_receding_horizon" --model "$models/sagittal_leg_r.json" --out "$results/sagittal_leg_r/receding_horizon"
echo "== figures"
# Debian's interpreter, which has python3-matplotlib (a python3 earlier on PATH may not).
python=/usr/bin/python3
[[ -x $python ]] || python=python3
"$python" "$root/scripts/plot_results.py" "$results" "$results/seated_knee_r" "$results/sagittal_leg_r"
echo "== animations (GIF) of every scenario; OpenSim motion files (.mot) of the imported models"
export PYTHONPATH="$root/build/python${PYTHONPATH:+:$PYTHONPATH}"
for run in open_loop:arm_richter_warner receding_horizon:arm_richter_warner \
           seated_knee_r/open_loop:seated_knee_r seated_knee_r/receding_horizon:seated_knee_r \
           sagittal_leg_r/open_loop:sagittal_leg_r sagittal_leg_r/receding_horizon:sagittal_leg_r; do
  folder=$results/${run%%:*}
  model=$models/${run##*:}.json
  "$python" -m flatsos.animation --model "$model" --states "$folder/simulation.sto" --out "$folder/motion.gif"
  if [[ $run == *_r ]]; then
    "$python" -m flatsos.sto --model "$model" --states "$folder/simulation.sto" --out "$folder/motion.mot"
  fi
done
echo "== batch study on Dask: the paper's plan for 1000 subjects of +-20 % muscle strength"
"$python" "$root/examples/strength_study/strength_study.py" --out "$results/strength_study"
echo "demo: results in $results"
