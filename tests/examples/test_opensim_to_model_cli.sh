#!/usr/bin/env bash
# opensim_to_model: --help, bad arguments exit 2 naming the option, bad input exits 1 naming the
# problem and writes nothing, a good run writes a model the other programs plan with.
# Usage: OPENSIM_TO_MODEL OPEN_LOOP RECEDING_HORIZON
set -u
convert=$1 ol=$2 rh=$3
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
# A shank on a pin knee with an extensor and a flexor, and their fitted lengths.
cat > "$tmp/knee.osim" <<'XML'
<?xml version="1.0" encoding="UTF-8" ?>
<OpenSimDocument Version="40500"><Model name="pin_knee"><gravity>0 -9.80665 0</gravity>
<BodySet><objects>
<Body name="shank"><mass>3.5</mass><mass_center>0 -0.2 0</mass_center><inertia>0.05 0.005 0.05 0 0 0</inertia></Body>
</objects></BodySet>
<JointSet><objects>
<PinJoint name="knee"><socket_parent_frame>/ground</socket_parent_frame><socket_child_frame>/bodyset/shank</socket_child_frame>
<coordinates><Coordinate name="knee_angle"><default_value>0</default_value><range>-2 0.2</range></Coordinate></coordinates></PinJoint>
</objects></JointSet>
<ForceSet><objects>
<Millard2012EquilibriumMuscle name="extensor"><max_isometric_force>1500</max_isometric_force><optimal_fiber_length>0.1</optimal_fiber_length><tendon_slack_length>0.2</tendon_slack_length></Millard2012EquilibriumMuscle>
<Millard2012EquilibriumMuscle name="flexor"><max_isometric_force>1000</max_isometric_force><optimal_fiber_length>0.1</optimal_fiber_length><tendon_slack_length>0.2</tendon_slack_length></Millard2012EquilibriumMuscle>
</objects></ForceSet></Model></OpenSimDocument>
XML
fitted() { echo "<FunctionBasedPath name=\"/forceset/$1\"><coordinate_paths>/jointset/knee/knee_angle</coordinate_paths><length_function><MultivariatePolynomialFunction><coefficients>$2</coefficients><dimension>1</dimension><order>1</order></MultivariatePolynomialFunction></length_function></FunctionBasedPath>"; }
echo "<OpenSimDocument><Set_FunctionBasedPath_><objects>$(fitted extensor "0.35 0.04")$(fitted flexor "0.30 -0.04")</objects></Set_FunctionBasedPath_></OpenSimDocument>" > "$tmp/paths.xml"
echo "<OpenSimDocument><Set_FunctionBasedPath_><objects>$(fitted extensor "0.35 0.04")$(fitted flexor "0.20 -0.04")</objects></Set_FunctionBasedPath_></OpenSimDocument>" > "$tmp/slack.xml"

args=(--osim "$tmp/knee.osim" --paths "$tmp/paths.xml")
expect 0 "--keep" -- "$convert" --help
expect 2 "--keep" -- "$convert" --osim "$tmp/knee.osim" --paths "$tmp/paths.xml" --out "$tmp/m.json"
expect 2 "not a finite number" -- "$convert" "${args[@]}" --keep knee_angle --hold knee_angle=abc --out "$tmp/m.json"
expect 2 "--range" -- "$convert" "${args[@]}" --keep knee_angle --range knee_angle=10 --out "$tmp/m.json"
expect 1 "cannot open the OpenSim model file" -- "$convert" --osim "$tmp/none.osim" --paths "$tmp/paths.xml" --keep knee_angle --out "$tmp/m.json"
expect 1 "kept coordinate 'hip': the OpenSim model has no such coordinate" -- "$convert" "${args[@]}" --keep hip --out "$tmp/m.json"
expect 1 "range of 'knee_angle'" -- "$convert" "${args[@]}" --keep knee_angle --range knee_angle=-150:30 --out "$tmp/m.json"
expect 1 "muscle 'flexor': its fitted length" -- "$convert" --osim "$tmp/knee.osim" --paths "$tmp/slack.xml" --keep knee_angle --refuse-slack-muscles --out "$tmp/m.json"
[[ -e "$tmp/m.json" ]] && { echo "FAILED: a failed conversion wrote a model"; fail=1; }
expect 0 "1 joint(s), 2 muscles, 1 bodies" -- "$convert" "${args[@]}" --keep knee_angle --range knee_angle=-90:0 --out "$tmp/m.json"
grep -q '"coordinate": "knee_angle"' "$tmp/m.json" || { echo "FAILED: the model lacks the kept coordinate"; fail=1; }
grep -q '"osim": "knee.osim"' "$tmp/m.json" || { echo "FAILED: the provenance lacks the source (by file name)"; fail=1; }
expect 0 "plan solved" -- "$ol" --model "$tmp/m.json" --q0-deg -80 --target-deg -20 --duration-s 1 --out "$tmp/ol"
# Without --paths the muscle paths are fitted to the model's GeometryPaths, each fit reported.
arm26="$(dirname "${BASH_SOURCE[0]}")/../../models/opensim/arm26/arm26.osim"
expect 0 "path of BRA fitted (order" -- "$convert" --osim "$arm26" --keep r_elbow_flex --hold r_shoulder_elev=0 --range r_elbow_flex=10:120 --out "$tmp/arm26.json"
grep -q '"path_fit"' "$tmp/arm26.json" || { echo "FAILED: the provenance lacks the path fit"; fail=1; }
# Both coordinates: TRIlat and TRImed cross the elbow along the same points with the same
# strength (tied muscles, every split of their load costs the same); the plan must still solve.
expect 0 "path of BRA fitted (order" -- "$convert" --osim "$arm26" --keep r_shoulder_elev r_elbow_flex --range r_shoulder_elev=-10:10 r_elbow_flex=5:100 --out "$tmp/arm26_both.json"
# arm26.osim as downloaded: no flat outputs serve OpenSim's ranges, so each run gets them over the
# region it visits; the plan and the controller both reach 90 deg.
expect 0 "chosen over the run's region" -- "$ol" --model "$arm26" --q0-deg 0 15 --target-deg 0 90 --duration-s 1 --out "$tmp/arm26_ol"
grep -q '"status": "solved"' "$tmp/arm26_ol/summary.json" || { echo "FAILED: arm26's 15 -> 90 deg plan was not solved"; fail=1; }
expect 0 "plan failures 0" -- "$rh" --model "$arm26" --q0-deg 0 15 --target-deg 0 90 --duration-s 2 --out "$tmp/arm26_rh"
# An .osim where a model is expected is imported on the way, with the import's report.
tug="$(dirname "${BASH_SOURCE[0]}")/../../models/opensim/Tug_of_War_Millard.osim"
# 4 cm: with Millard's curves (fL 0 below 0.4441 optimal lengths) the shortened muscle at full
# activation holds the lengthened one's passive pull only up to 4.23 cm (at 5 cm: 0.094 against
# 0.49 Fmax), so no excitation holds the block at 5 cm.
expect 0 "range of block_tz narrowed" -- "$ol" --model "$tug" --q0-deg 0 --target-deg 0.04 --duration-s 1 --out "$tmp/tug"
grep -q '"status": "solved"' "$tmp/tug/summary.json" || { echo "FAILED: the block's 4 cm plan was not solved"; fail=1; }
# The controller holds the block at 2 cm against a 20 N push from 1 s on.
printf 'push\nversion=1\nendheader\ntime\tblock_tz\n0\t0\n1\t20\n' > "$tmp/push.sto"
expect 0 "plan failures 0" -- "$rh" --model "$tug" --q0-deg 0 --target-deg 0.02 --duration-s 3 --disturbance "$tmp/push.sto" --out "$tmp/tug_rh"
grep -q '"disturbance_file"' "$tmp/tug_rh/summary.json" || { echo "FAILED: the summary does not name the push"; fail=1; }
expect 2 "disturbance" -- "$rh" --model "$tug" --disturbance "$tmp/none.sto" --out "$tmp/tug_rh2"
# The left leg of OpenSim's example model with OpenSim's ranges and no other option: the
# controller settles (the program exits 1 when it does not). Its Millard soleus carries much
# passive force, which a disturbance observer that mistook each plan's own muscle states for a
# disturbance let creep the ankle away (session 43).
shared="$(dirname "${BASH_SOURCE[0]}")/../../../shared/opensim"
if [[ -n "${FLATSOS_SANITIZER_RUN:-}" ]]; then
  echo "skipped: the left leg's controller run (the sanitizer run leaves it to the Release suite)"
elif [[ -f "$shared/subject_walk_scaled.osim" ]]; then
  expect 0 "3 joint(s), 33 muscles" -- "$convert" --osim "$shared/subject_walk_scaled.osim" --paths "$shared/subject_walk_scaled_FunctionBasedPathSet.xml" --keep hip_flexion_l knee_angle_l ankle_angle_l --out "$tmp/leg_l.json"
  expect 0 "plan failures 0" -- "$rh" --model "$tmp/leg_l.json" --target-deg 40 60 10 --duration-s 2 --out "$tmp/leg_rh"
else
  echo "skipped: the left leg of OpenSim's example model (not beside the repository: $shared)"
fi
exit $fail
