#!/usr/bin/env bash
# track_motion: --help, bad arguments exit 2 naming the option, a motion without the model's
# coordinates exits 1 naming one, a task that leaves its tolerance exits 1 with complete files
# and the reason in the summary, and arm26 as downloaded follows OpenSim's CMC tutorial motion
# (squared excitations) writing CMC's three tables.
# Usage: TRACK_MOTION
set -u
tm=$1
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
models="$(dirname "${BASH_SOURCE[0]}")/../../models"
arm26="$models/opensim/arm26"
paper="$models/arm_richter_warner.json"
expect 0 "--coordinates" -- "$tm" --help
expect 2 "--coordinates" -- "$tm" --model "$paper" --out "$tmp/o"
expect 2 "--correction-s" -- "$tm" --model "$paper" --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --correction-s 0.6 --out "$tmp/o"
expect 2 "--effort" -- "$tm" --model "$paper" --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --effort squared --out "$tmp/o"
expect 1 "no column for the coordinate 'shoulder'" -- "$tm" --model "$paper" --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/o"
# The paper's arm through a smooth 40 deg swing of both joints in 1 s.
{ printf 'swing\nversion=1\ninDegrees=yes\nendheader\ntime\tshoulder\telbow\n'
  for i in $(seq 0 100); do awk -v i="$i" 'BEGIN { x = i / 100; s = x * x * (3 - 2 * x); printf "%.2f\t%.6f\t%.6f\n", x, 30 + 40 * s, 40 + 40 * s }'; done; } > "$tmp/swing.mot"
expect 0 "plan failures 0" -- "$tm" --model "$paper" --coordinates "$tmp/swing.mot" --out "$tmp/paper"
grep -q '"success": true' "$tmp/paper/summary.json" || { echo "FAILED: the paper's arm did not follow the swing"; fail=1; }
# The same with a tolerance no controller meets: exit 1, files complete, the reason given.
expect 1 "left the reference by" -- "$tm" --model "$paper" --coordinates "$tmp/swing.mot" --tolerance-deg 1e-6 --out "$tmp/strict"
grep -q '"success": false' "$tmp/strict/summary.json" || { echo "FAILED: a failed task reported success"; fail=1; }
[ -s "$tmp/strict/arm_richter_warner_pErr.sto" ] || { echo "FAILED: the failed task left no position errors"; fail=1; }
# arm26 as downloaded with OpenSim 2.x's muscles (those of the tutorial's CMC run), each plan
# minimizing its squared excitations.
expect 0 "plan failures 0" -- "$tm" --model "$arm26/arm26.osim" --opensim-2-muscles --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --effort excitation_squared --out "$tmp/arm26"
grep -q '"effort": "excitation_squared"' "$tmp/arm26/summary.json" || { echo "FAILED: the summary does not name the effort"; fail=1; }
# Squared excitations cost 0.247 here, the paper's linear effort 0.334 (measured).
python3 -c 'import json, sys; s = json.load(open(sys.argv[1])); sys.exit(0 if s["excitation_squared_integral"] < 0.28 else 1)' \
  "$tmp/arm26/summary.json" || { echo "FAILED: the squared-excitation run spent as much as the linear effort's"; fail=1; }
for f in states controls pErr; do [ -s "$tmp/arm26/arm26_$f.sto" ] || { echo "FAILED: arm26_$f.sto missing"; fail=1; }; done
head -8 "$tmp/arm26/arm26_pErr.sto" | grep -q "^time	r_shoulder_elev	r_elbow_flex$" || { echo "FAILED: the position errors lack CMC's columns"; fail=1; }
# The same motion with arm26's muscles replaced as OpenSim Moco's MocoInverse and MocoTrack
# examples replace them (DeGroote-Fregly 2016, passive force ignored).
expect 2 "--degroote-muscles" -- "$tm" --model "$arm26/arm26.osim" --ignore-passive-fiber-forces --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/o"
expect 2 "--opensim-2-muscles" -- "$tm" --model "$arm26/arm26.osim" --degroote-muscles --opensim-2-muscles --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/o"
expect 0 "plan failures 0" -- "$tm" --model "$arm26/arm26.osim" --degroote-muscles --ignore-passive-fiber-forces --coordinates "$arm26/inverse_kinematics/arm26_InverseKinematics.mot" --out "$tmp/arm26_dgf"
grep -q '"success": true' "$tmp/arm26_dgf/summary.json" || { echo "FAILED: arm26 with DeGroote-Fregly muscles did not follow the motion"; fail=1; }
exit $fail
