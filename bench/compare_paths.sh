#!/usr/bin/env bash
# The cost of muscle geometry: the open-loop SOP and one inverse-map evaluation on the paper's
# arm written three ways, in one interleaved run:
#   constant         its constant moment arms (moment_arms_m), as shipped;
#   order-1 paths    the same arm with each length an order-1 polynomial path (identical model);
#   nonlinear paths  the biceps' elbow moment arm 0.02 -> 0.04 m over 0-90 deg (a cubic in the
#                    elbow, linear in the shoulder) and the brachialis' 0.02 -> 0.044 m (a
#                    quadratic), everything else as shipped.
# All three plan the same transfer (10, 20 -> 60, 90 deg in 3 s from the minimum-effort rest
# state, 10 N reserves; the paper's own scenario dips the elbow below 0 deg, where the shipped
# triceps' tendon would be slack and the polynomial paths have no range). Given a second bench
# program (another build), it runs the constant arm with it too, beside the others.
#
# Usage: bench/compare_paths.sh BENCH [BASELINE_BENCH] [ROUNDS=5]
# Prints one line per model and build: the best (over rounds) median of each stage.
set -euo pipefail
bench=${1:?usage: bench/compare_paths.sh BENCH [BASELINE_BENCH] [ROUNDS]}
baseline=${2:-}
rounds=${3:-5}
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

python3 - "$root/models/arm_richter_warner.json" "$tmp" <<'PY'
import copy, json, sys
arm = json.load(open(sys.argv[1]))
out = sys.argv[2]
arm["scenarios"] = {"open_loop": {"q0_deg": [10.0, 20.0], "target_deg": [60.0, 90.0], "duration_s": 3.0, "reserves_N": 10.0}}
json.dump(arm, open(out + "/constant.json", "w"))
ordered = copy.deepcopy(arm)
coordinates = ["shoulder_flexion", "elbow_flexion"]
for joint, coordinate, rng in zip(ordered["joints"], coordinates, [[0.0, 1.8], [0.0, 2.5]]):
    joint["coordinate"] = coordinate
    joint["range_rad"] = rng
for muscle in ordered["muscles"]:
    arms = muscle.pop("moment_arms_m")
    crossed = [(c, arms[j["name"]]) for j, c in zip(ordered["joints"], coordinates) if j["name"] in arms]
    # Order 1 in OpenSim's order: 1, then the last coordinate, ..., the first; L = L0 - r . q.
    coefficients = [muscle.pop("length_at_zero_angles_m")] + [-r for _, r in reversed(crossed)]
    muscle["path"] = {"coordinates": [c for c, _ in crossed], "order": 1, "coefficients": coefficients}
json.dump(ordered, open(out + "/order1.json", "w"))
nonlinear = copy.deepcopy(ordered)
for muscle in nonlinear["muscles"]:
    if muscle["name"] == "biceps":  # 1, E, E^2, E^3, S, SE, SE^2, S^2, S^2 E, S^3
        muscle["path"] = {"coordinates": coordinates, "order": 3,
                          "coefficients": [0.4283, -0.02, -0.011140846016432676, 0.0020264236728467556,
                                           -0.03, 0.0, 0.0, 0.0, 0.0, 0.0]}
    if muscle["name"] == "brachialis":
        muscle["path"] = {"coordinates": ["elbow_flexion"], "order": 2,
                          "coefficients": [0.1681, -0.02, -0.00477464829275686]}
json.dump(nonlinear, open(out + "/nonlinear.json", "w"))
PY

runs=("constant $bench $tmp/constant.json" "order-1_paths $bench $tmp/order1.json" "nonlinear_paths $bench $tmp/nonlinear.json")
[[ -n $baseline ]] && runs+=("constant_baseline $baseline $tmp/constant.json")
for ((r = 0; r < rounds; ++r)); do
  for run in "${runs[@]}"; do
    read -r name program model <<<"$run"
    "$program" --open-loop-only --model "$model" > "$tmp/$name.$r.json"
  done
done
python3 - "$tmp" "$rounds" "${runs[@]}" <<'PY'
import json, sys
tmp, rounds, runs = sys.argv[1], int(sys.argv[2]), sys.argv[3:]
print(f"{'model':<20} {'SOP setup+solve+cert ms':>24} {'cost N s':>10} {'inverse map us':>15} {'inverse dynamics us':>20}")
for run in runs:
    name = run.split()[0]
    r = [json.load(open(f"{tmp}/{name}.{k}.json")) for k in range(rounds)]
    best = lambda f: min(f(x) for x in r)
    sop = r[0]["open_loop_sop"]
    print(f"{name:<20} {best(lambda x: x['open_loop_sop']['setup_plus_solve']['median']):>24.3f} "
          f"{sop.get('cost_Ns', float('nan')):>10.3f} {best(lambda x: x['inverse_map_one_time']['median']):>15.3f} "
          f"{best(lambda x: x['inverse_dynamics_one_call']['median']):>20.3f}")
PY
