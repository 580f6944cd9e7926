#!/usr/bin/env bash
# arm_open_loop and arm_receding_horizon: --help, bad arguments exit 2 naming the option, bad
# models exit 1 naming the problem, good runs write their files. Usage: OPEN_LOOP RH
set -u
ol=$1 rh=$2
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
models=$(cd "$(dirname "${BASH_SOURCE[0]}")/../../models" && pwd)
expect 0 "--pieces" -- "$ol" --help
expect 2 "--target-deg" -- "$ol" --target-deg 90 --out "$tmp/o"
expect 2 "--reserves-N" -- "$ol" --reserves-N 1,2,3 --out "$tmp/o"
expect 2 "--pieces" -- "$ol" --pieces -1 --out "$tmp/o"
expect 2 "--duration-s" -- "$ol" --duration-s -3 --out "$tmp/o"
printf '{"bodies": []}' > "$tmp/bad.json"
expect 1 "bodies: must not be empty" -- "$ol" --model "$tmp/bad.json" --out "$tmp/o"
# The paper's single box: infeasible, exit 1, a summary that says why, no simulation.
expect 1 "infeasible" -- "$ol" --paper --pieces 1 --degree 0 --out "$tmp/box"
grep -q '"status": "infeasible"' "$tmp/box/summary.json" || { echo "FAILED: box summary lacks the status"; fail=1; }
[[ ! -e "$tmp/box/simulation.sto" ]] || { echo "FAILED: a failed plan left a simulation"; fail=1; }
# The open-loop simulation's integrator is chosen and recorded like the other programs'.
expect 2 "--integrator" -- "$ol" --integrator euler --out "$tmp/o"
expect 0 "simulated open loop" -- "$ol" --paper --integrator rosenbrock --accuracy 1e-6 --out "$tmp/olr"
grep -q '"integrator": "rosenbrock"' "$tmp/olr/summary.json" || { echo "FAILED: open-loop summary does not name the integrator"; fail=1; }
# By default the integrator is chosen (auto): the elbow's muscles are not stiff, Runge-Kutta-Merson.
expect 0 "(rkm)" -- "$ol" --model "$models/elbow_1dof.json" --out "$tmp/ola"
grep -q '"integrator": "rkm"' "$tmp/ola/summary.json" || { echo "FAILED: the automatic choice is not named"; fail=1; }
# A replay past its step limit fails the task, says why, and keeps what it simulated (an unstable
# plan's explicit replay can otherwise run for hours).
expect 2 "--max-integrator-steps" -- "$ol" --max-integrator-steps -1 --out "$tmp/o"
expect 1 "the step limit" -- "$ol" --max-integrator-steps 100 --out "$tmp/olsl"
grep -q '"step_limit_reached": true' "$tmp/olsl/summary.json" || { echo "FAILED: the summary does not say the step limit stopped the replay"; fail=1; }
grep -q '"success": false' "$tmp/olsl/summary.json" || { echo "FAILED: a replay stopped at its step limit reported success"; fail=1; }
grep -q 'success=false' "$tmp/olsl/simulation.sto" || { echo "FAILED: the stopped replay's table does not say so"; fail=1; }
# The paper's plan certifies its pieces in closed form: no Ipopt call, and no linear solver named.
# The whole program as one Ipopt problem names the linear solver that served its calls.
grep -q '"ipopt_calls": 0' "$tmp/olr/summary.json" || { echo "FAILED: the paper's plan called Ipopt"; fail=1; }
grep -q '"ipopt_linear_solver": ""' "$tmp/olr/summary.json" || { echo "FAILED: a linear solver is named without an Ipopt call"; fail=1; }
expect 0 "KKT systems by" -- "$ol" --paper --sos-method whole_program_nlp --out "$tmp/olw"
grep -q '"ipopt_linear_solver": "[^"]' "$tmp/olw/summary.json" || { echo "FAILED: the summary does not name Ipopt's linear solver"; fail=1; }
# The reserves' program as one Ipopt problem: the same plan (the summary names the method and the
# NLP's size); an unknown method exits 2, and the free path, which needs the exchange, exits 1.
expect 2 "--sos-method" -- "$ol" --sos-method sdp --out "$tmp/o"
expect 2 "--free-path-method" -- "$ol" --free-path-method bfgs --free-path-spans 2 --out "$tmp/o"
expect 2 "--free-path-span-growth" -- "$ol" --free-path-span-growth 0 --free-path-spans 2 --out "$tmp/o"
# A free path on graded spans: its summary gives the knots the coefficients need.
expect 0 "simulated open loop" -- "$ol" --flat-output-degree 3 --flat-output-spans 12 --free-path-spans 6 \
  --free-path-span-growth 1.3 --integrator rosenbrock --accuracy 1e-6 --out "$tmp/olg"
grep -q '"q_breakpoints_s": \[' "$tmp/olg/summary.json" || { echo "FAILED: the summary lacks the free path's knots"; fail=1; }
# Its start plan: in the flat outputs' own 12 spans (none nested has 16 or more).
grep -q '"start_flat_output_spans": 12' "$tmp/olg/summary.json" || { echo "FAILED: the summary lacks the start plan's spans"; fail=1; }
expect 2 "--free-path-start-min-spans" -- "$ol" --free-path-start-min-spans -1 --free-path-spans 2 --out "$tmp/o"
expect 2 "--free-path-exchange-tolerance" -- "$ol" --free-path-exchange-tolerance -1e-3 --free-path-spans 2 --out "$tmp/o"
expect 0 "simulated open loop" -- "$ol" --paper --sos-method whole_program_nlp --no-bounds --integrator rosenbrock --accuracy 1e-6 --out "$tmp/olw"
grep -q '"sos_method": "whole_program_nlp"' "$tmp/olw/summary.json" || { echo "FAILED: the summary does not name the SOS method"; fail=1; }
grep -q '"equalities": 368' "$tmp/olw/summary.json" || { echo "FAILED: the summary lacks the whole-program NLP's size"; fail=1; }
grep -q '"whole_program_nlp_solve_seconds"' "$tmp/olw/summary.json" || { echo "FAILED: the summary does not time the NLP under its name"; fail=1; }
grep -q '"cost_Ns": 958.3213' "$tmp/olw/summary.json" || { echo "FAILED: the whole-program NLP's cost is not the exchange's"; fail=1; }
expect 1 "free_path plans by the exchange method" -- "$ol" --sos-method whole_program_nlp --free-path-spans 2 --out "$tmp/o"
# A nonlinear effort (squared excitations): planned along the prescribed path and named with its
# value and unit in the summary; an unknown name exits 2; with the path free it is planned by the
# reduced quasi-Newton method (the elbow, 12 spans growing by 1.2), and the joint Newton method
# exits 1 naming why.
expect 0 "excitation_squared 0.2349" -- "$ol" --effort excitation_squared --integrator rosenbrock --accuracy 1e-6 --out "$tmp/ole"
grep -q '"effort": "excitation_squared"' "$tmp/ole/summary.json" || { echo "FAILED: the summary does not name the effort"; fail=1; }
grep -q '"effort_unit": "s"' "$tmp/ole/summary.json" || { echo "FAILED: the summary lacks the effort's unit"; fail=1; }
expect 2 "--effort" -- "$ol" --effort squared --out "$tmp/o"
expect 1 "takes the method 'reduced_quasi_newton'" -- "$ol" --effort excitation_squared --free-path-spans 2 --free-path-method joint_newton --out "$tmp/o"
expect 0 "excitation_squared 0.0089" -- "$ol" --model "$models/elbow_1dof.json" --effort excitation_squared --free-path-spans 12 --free-path-span-growth 1.2 --integrator rosenbrock --accuracy 1e-6 --out "$tmp/olef"
grep -q '"optimized": true' "$tmp/olef/summary.json" || { echo "FAILED: the summary does not say the path was optimized"; fail=1; }
# The shortest transfer: found, simulated over that duration, every plan of the search in the
# summary; a longest duration without a plan fails the task.
expect 2 "--shortest-time-ratio" -- "$ol" --shortest-time --shortest-time-ratio 1.5 --out "$tmp/o"
expect 0 "shortest transfer solved, 1.365 s" -- "$ol" --paper --shortest-time --duration-s 3 --integrator rosenbrock --accuracy 1e-6 --out "$tmp/ost"
grep -q '"shortest_duration_s": 1.365' "$tmp/ost/summary.json" || { echo "FAILED: the summary lacks the shortest duration"; fail=1; }
grep -q '"below_status": "infeasible"' "$tmp/ost/summary.json" || { echo "FAILED: the summary lacks the verdict below it"; fail=1; }
expect 1 "no plan at the longest duration, 1 s" -- "$ol" --paper --shortest-time --duration-s 1 --out "$tmp/ost_none"
grep -q '"success": false' "$tmp/ost_none/summary.json" || { echo "FAILED: a search without a plan reported success"; fail=1; }
[[ ! -e "$tmp/ost_none/simulation.sto" ]] || { echo "FAILED: a search without a plan left a simulation"; fail=1; }
expect 0 "--horizon-s" -- "$rh" --help
expect 2 "--period-s" -- "$rh" --period-s 1.0 --horizon-s 0.5 --out "$tmp/o"
expect 2 "--slp-solver" -- "$rh" --slp-solver glpk --out "$tmp/o"
expect 2 "--q0-deg" -- "$rh" --q0-deg 1,2,3 --out "$tmp/o"
expect 2 "--integrator" -- "$rh" --integrator euler --out "$tmp/o"
expect 2 "--observer-gain-per-s" -- "$rh" --observer-gain-per-s 2000 --out "$tmp/o"
expect 0 "settling" -- "$rh" --duration-s 1.5 --out "$tmp/rh"
grep -q '"integrator_accuracy": 1e-05' "$tmp/rh/summary.json" || { echo "FAILED: rosenbrock default accuracy not 1e-5"; fail=1; }
grep -q '"success": true' "$tmp/rh/summary.json" || { echo "FAILED: a settled run is not a success"; fail=1; }
# Bounded steps (the default) leave nothing to clamp; the paper's step clamps the first period.
grep -q '"excitation_clamps": 0,' "$tmp/rh/summary.json" || { echo "FAILED: bounded steps clamped excitations"; fail=1; }
# A plant 20 % weaker than the model: the default observer reaches the target; the paper's
# controller (no observer) ends short of it and fails its task.
expect 0 "settling" -- "$rh" --plant-strength 0.8 --out "$tmp/rh_weak"
python3 - "$tmp/rh_weak/summary.json" <<'PY' || { echo "FAILED: the weaker plant did not end within 1 deg, or the summary lacks it"; fail=1; }
import json, sys
s = json.load(open(sys.argv[1]))
assert s["plant"]["strength"] == 0.8 and s["observer_gain_per_s"] == 40.0, s["plant"]
assert max(abs(a - b) for a, b in zip(s["final_q_deg"], s["target_q_deg"])) < 1.0, s["final_q_deg"]
PY
expect 1 "never settled" -- "$rh" --paper --plant-strength 0.8 --out "$tmp/rh_weak_paper"
grep -q '"observer_gain_per_s": 0.0' "$tmp/rh_weak_paper/summary.json" || { echo "FAILED: --paper kept the observer"; fail=1; }
expect 1 "plant" -- "$rh" --plant "$models/elbow_1dof.json" --out "$tmp/o"
expect 1 "bounded steps 0" -- "$rh" --duration-s 0.2 --no-excitation-bounds --out "$tmp/rh_paper"
grep -q '"enforced": false' "$tmp/rh_paper/summary.json" || { echo "FAILED: --no-excitation-bounds not in the summary"; fail=1; }
grep -q '"excitation_clamps": 0,' "$tmp/rh_paper/summary.json" && { echo "FAILED: the paper's step clamped nothing"; fail=1; }
# A run that never reaches its target fails its task: exit 1, the reason in the summary, the files complete.
expect 1 "never settled within 1 deg of the target in 0.1 s" -- "$rh" --duration-s 0.1 --integrator bdf --observer-gain-per-s 20 --out "$tmp/rhb"
grep -q '"integrator_accuracy": 1e-08' "$tmp/rhb/summary.json" || { echo "FAILED: bdf default accuracy not 1e-8"; fail=1; }
grep -q '"success": false' "$tmp/rhb/summary.json" || { echo "FAILED: an unsettled run reported success"; fail=1; }
grep -q '"message": "never settled' "$tmp/rhb/summary.json" || { echo "FAILED: the summary does not say why the run failed"; fail=1; }
[[ -s "$tmp/rhb/simulation.sto" ]] || { echo "FAILED: a failed run's simulation is missing"; fail=1; }
# A 10 kg forearm: held at the start, but the muscles cannot lift it to the target (clamped
# excitations, the arm falls away); the run says so and exits 1.
sed 's/"mass_kg": 1.76/"mass_kg": 10/' "$models/arm_richter_warner.json" > "$tmp/heavy.json"
expect 1 "never settled" -- "$rh" --model "$tmp/heavy.json" --out "$tmp/heavy"
# A 60 kg forearm cannot even be held at the start: the error names the muscle and the quantity.
sed 's/"mass_kg": 1.76/"mass_kg": 60/' "$models/arm_richter_warner.json" > "$tmp/heavier.json"
expect 1 "infeasible: no constant flat outputs keep every excitation in [0, 1] and activation in [floor, 1] over the first period with the reserves; closest: muscle 'anterior_deltoid' at t = 0 s: activation" -- "$rh" --model "$tmp/heavier.json" --out "$tmp/heavier"
for f in simulation.sto simulation_controls.sto predictions/step_0000.sto predictions/step_0029.sto summary.json; do
  [[ -s "$tmp/rh/$f" ]] || { echo "FAILED: $f missing"; fail=1; }
done
# OpenSim's TimeSeriesTable needs strictly increasing time in every file.
increasing() {  # rows after the labels line: time strictly above the previous row's
  awk -F'\t' 'body && NR > start + 2 && $1 + 0 <= last { bad = 1 } body && NR > start + 1 { last = $1 + 0 }
              /^endheader$/ { body = 1; start = NR } END { exit bad }' "$1"
}
for f in "$tmp"/rh/predictions/*.sto "$tmp/rh/simulation.sto" "$tmp/rh/simulation_controls.sto"; do
  increasing "$f" || { echo "FAILED: time does not increase strictly in $f"; fail=1; }
done
[[ $(ls "$tmp/rh/predictions" | wc -l) == 30 ]] || { echo "FAILED: not one prediction per step"; fail=1; }
for f in plan.sto plan_controls.sto simulation.sto simulation_controls.sto; do
  [[ -s "$tmp/olr/$f" ]] || { echo "FAILED: open loop $f missing"; fail=1; }
done
grep -q '"real_time_factor"' "$tmp/rh/summary.json" || { echo "FAILED: RH summary lacks real_time_factor"; fail=1; }
# Any model: a 1-joint elbow plans and controls with the defaults of its own scenarios, and with
# none (a copy without "scenarios": start at 0 deg at rest, target 30 deg).
expect 0 "simulated open loop 1.5 s" -- "$ol" --model "$models/elbow_1dof.json" --out "$tmp/elbow_ol"
grep -q "/jointset/elbow/elbow_flexion/value" "$tmp/elbow_ol/plan.sto" || { echo "FAILED: the coordinate's own name is not used"; fail=1; }
expect 0 "settling" -- "$rh" --model "$models/elbow_1dof.json" --out "$tmp/elbow_rh"
grep -q '"target_deg": \[' "$tmp/elbow_rh/summary.json" || { echo "FAILED: the summary lacks the inputs"; fail=1; }
python3 -c 'import json, sys; m = json.load(open(sys.argv[1])); del m["scenarios"]; json.dump(m, open(sys.argv[2], "w"))' \
  "$models/elbow_1dof.json" "$tmp/bare.json"
expect 0 "simulated open loop 3 s" -- "$ol" --model "$tmp/bare.json" --out "$tmp/bare_ol"
grep -q '"a0": "minimum-effort rest state"' "$tmp/bare_ol/summary.json" || { echo "FAILED: bare model did not start at rest"; fail=1; }
expect 0 "settling" -- "$rh" --model "$tmp/bare.json" --out "$tmp/bare_rh"
expect 2 "--q0-deg: expects 1 comma-separated values" -- "$ol" --model "$tmp/bare.json" --q0-deg 0,10 --out "$tmp/o"
# A model without flat_outputs: the library chooses E, says which and with what margin, and the
# effort is the sum of normalized tendon forces (3 joints, 8 muscles, posture-dependent paths).
expect 0 "simulated open loop 1.5 s" -- "$ol" --model "$models/arm_wrist_8_muscles.json" --flat-output-spans 8 --out "$tmp/arm8_ol"
python3 - "$tmp/arm8_ol/summary.json" <<'PY' || { echo "FAILED: the summary lacks the library's flat outputs"; fail=1; }
import json, sys
p = json.load(open(sys.argv[1]))["problem"]
assert p["flat_outputs"]["chosen_by"] == "library", p
assert len(p["flat_outputs"]["rows"]) == 5, p
assert 0 < p["flat_outputs"]["assumption1_margin"]["value"] <= 1, p
assert p["effort_weights"]["kind"] == "normalized_tendon_force", p
assert set(p["joint_limits"]) == {"shoulder", "elbow", "wrist"}, p
PY
expect 0 "settling" -- "$rh" --model "$models/arm_wrist_8_muscles.json" --out "$tmp/arm8_rh"
grep -q '"chosen_by": "library"' "$tmp/arm8_rh/summary.json" || { echo "FAILED: the RH summary lacks the flat outputs"; fail=1; }
# Units: an implausible value is planned with a warning naming the field, kept in the summary; an
# impossible target (no tendon can be taut there) is an error naming the muscle.
sed 's/"length_m": 0.32/"length_m": 32/' "$models/elbow_1dof.json" > "$tmp/long.json"
expect 0 "arm_open_loop: warning: bodies[0] 'forearm'.length_m: 32 m is above 3 m" -- "$ol" --model "$tmp/long.json" --out "$tmp/long"
grep -q "bodies\[0\] 'forearm'.length_m" "$tmp/long/summary.json" || { echo "FAILED: the warning is not in the summary"; fail=1; }
expect 1 "target joint angles: the musculotendon path of 'anterior_deltoid' would be" -- "$ol" --target-deg 400,0 --out "$tmp/o"
expect 1 "target joint angles: the musculotendon path of 'anterior_deltoid' would be" -- "$rh" --target-deg 400,0 --out "$tmp/o"
exit $fail
