#!/usr/bin/env bash
# static_optimization: --help, bad arguments exit 2 naming the option, a motion the muscles
# cannot make exits 1 naming the joint (files complete, the reason in the summary), and arm26
# as downloaded along OpenSim's tutorial motion writes OpenSim's two tables.
# Usage: STATIC_OPTIMIZATION
set -u
so=$1
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
models="$(dirname "${BASH_SOURCE[0]}")/../../models"
arm26="$models/opensim/arm26"
expect 0 "--coordinates" -- "$so" --help
expect 2 "--coordinates" -- "$so" --model "$models/arm_richter_warner.json" --out "$tmp/o"
expect 2 "--activation-exponent" -- "$so" --model "$models/arm_richter_warner.json" --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --activation-exponent 1 --out "$tmp/o"
expect 1 "no column for the coordinate 'shoulder'" -- "$so" --model "$models/arm_richter_warner.json" --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/o"
# The paper's arm swung through 2400 deg in 1 s: no activation in [0, 1] can do it.
{ printf 'fast\nversion=1\ninDegrees=yes\nendheader\ntime\tshoulder\telbow\n'
  for i in $(seq 0 100); do awk -v i="$i" 'BEGIN { x = i / 100; s = x * x * (3 - 2 * x); printf "%.2f\t%.6f\t%.6f\n", x, 20 + 60 * s, 20 + 2400 * s }'; done; } > "$tmp/fast.mot"
expect 1 "the muscles cannot produce the torque about" -- "$so" --model "$models/arm_richter_warner.json" --coordinates "$tmp/fast.mot" --out "$tmp/fast"
grep -q '"success": false' "$tmp/fast/summary.json" || { echo "FAILED: a failed run reported success"; fail=1; }
expect 0 "0 failed" -- "$so" --model "$models/arm_richter_warner.json" --coordinates "$tmp/fast.mot" --reserve-optimal-torque-N-m 100 --out "$tmp/reserves"
grep -q 'elbow_reserve' "$tmp/reserves/arm_richter_warner_StaticOptimization_force.sto" || { echo "FAILED: the reserves' column is missing"; fail=1; }
# arm26 as downloaded, OpenSim 2.x's muscles (the tutorial's results were made with them).
expect 0 "121 frames" -- "$so" --model "$arm26/arm26.osim" --opensim-2-muscles --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/arm26"
head -8 "$tmp/arm26/arm26_StaticOptimization_activation.sto" | grep -q "^time	TRIlong	TRIlat	TRImed	BIClong	BICshort	BRA$" || { echo "FAILED: the activation table lacks OpenSim's columns"; fail=1; }
grep -q '"strength_rule": "opensim2"' "$tmp/arm26/summary.json" || { echo "FAILED: the summary does not name OpenSim 2.x's rule"; fail=1; }
# With MocoInverse's muscles (fitted paths: faster), to compare with the inverse problem.
expect 0 "121 frames" -- "$so" --model "$arm26/arm26.osim" --degroote-muscles --ignore-passive-fiber-forces --paths fitted --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/arm26_dgf"
expect 2 "--degroote-muscles" -- "$so" --model "$arm26/arm26.osim" --ignore-passive-fiber-forces --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/o"
exit $fail
