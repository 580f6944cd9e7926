#!/usr/bin/env bash
# The main job: installs what is missing, builds, and runs the examples; results go to results/.
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
"$root/scripts/install_deps.sh"
"$root/scripts/build.sh"
mkdir -p "$root/results"
if [[ -x "$root/build/bin/arm_forward" ]]; then
  echo "== arm_forward: the muscle-driven arm held by its equilibrium activations for 1 s"
  "$root/build/bin/arm_forward" --q0-deg 0,10 --a0 0.135,0.040,0.404,0.556,0.414,0.068 \
    --equilibrate-tendons --duration 1.0 --out "$root/results/arm_forward"
fi
echo "demo: results in $root/results"
