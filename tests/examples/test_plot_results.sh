#!/usr/bin/env bash
# scripts/plot_results.py: figures for every program's output on both models, one output folder
# or a parent of several; errors name the file and exit 1; every activation/excitation panel of a
# figure shares one y-axis from 0 (checked against the data in the .sto files).
# Usage: FORWARD OPEN_LOOP RH SOURCE_DIR
set -u
fw=$1 ol=$2 rh=$3 src=$4
source "$(dirname "${BASH_SOURCE[0]}")/expect.sh"
python=/usr/bin/python3  # Debian's, which has python3-matplotlib
[[ -x $python ]] || python=python3
plot=("$python" "$src/scripts/plot_results.py")
is_png() { [[ $(head -c 8 "$1" | od -An -tx1 | tr -d ' \n') == 89504e470d0a1a0a ]]; }
check_pngs() {  # check_pngs <folder> <name>...: each exists and is a PNG, no temporary left
  local folder=$1 name; shift
  for name in "$@"; do
    is_png "$folder/$name" || { echo "FAILED: $folder/$name missing or not a PNG"; fail=1; }
  done
  [[ -z $(find "$folder" -maxdepth 1 -name '.*.tmp') ]] || { echo "FAILED: a temporary file left in $folder"; fail=1; }
}

for model in arm_richter_warner elbow_1dof; do
  runs=$tmp/$model m=$src/models/$model.json
  expect 0 "simulated open loop" -- "$ol" --model "$m" --out "$runs/open_loop"
  # 0.5 s is too short to settle (exit 1), but the files are complete and worth plotting.
  "$rh" --model "$m" --duration-s 0.5 --out "$runs/receding_horizon" >/dev/null 2>&1
  [[ -s $runs/receding_horizon/simulation.sto ]] || { echo "FAILED: $model receding horizon wrote no simulation"; fail=1; }
  expect 0 "wrote" -- "$fw" --model "$m" --equilibrate-tendons --duration-s 0.2 --out "$runs/forward"
  expect 0 "open_loop_joints_forces.png" -- "${plot[@]}" "$runs/open_loop"
  check_pngs "$runs/open_loop" open_loop_activations.png open_loop_joints_forces.png
  expect 0 "rh_activations.png" -- "${plot[@]}" "$runs/receding_horizon"
  check_pngs "$runs/receding_horizon" rh_joint_angles.png rh_activations.png
  expect 0 "forward_states.png" -- "${plot[@]}" "$runs/forward"
  check_pngs "$runs/forward" forward_states.png
done
# A muscle at 0.5 next to two nearly silent ones (a = 0.002).
expect 0 "wrote" -- "$fw" --model "$src/models/elbow_1dof.json" --a0 0.5 0.002 0.002 --equilibrate-tendons \
  --duration-s 0.2 --out "$tmp/elbow_1dof/silent"

# Parent folders: every output folder below them, one line per figure, with the scales reported.
rm -f "$tmp"/*/*/*.png
out=$("${plot[@]}" --report-scales "$tmp/arm_richter_warner" "$tmp/elbow_1dof" 2>&1); rc=$?
[[ $rc == 0 ]] || { echo "FAILED: plotting the parent folders exited $rc:"; echo "$out" | head -5; fail=1; }
[[ $(grep -c "^plot_results: wrote " <<<"$out") == 11 ]] || { echo "FAILED: not 11 figures from the parent folders:"; echo "$out"; fail=1; }
for d in "$tmp"/*/open_loop; do check_pngs "$d" open_loop_activations.png open_loop_joints_forces.png; done
for d in "$tmp"/*/receding_horizon; do check_pngs "$d" rh_joint_angles.png rh_activations.png; done
for d in "$tmp"/*/forward "$tmp/elbow_1dof/silent"; do check_pngs "$d" forward_states.png; done

# Shared scale: in each activation figure, one panel per muscle, all with the same limits, from 0
# (lower only if the data go below 0), holding the data, and not so high that activity looks flat.
grep '^{' <<<"$out" > "$tmp/scales.jsonl"
"$python" - "$tmp/scales.jsonl" <<'EOF' || fail=1
import json, os, sys

def columns(path, keep):
    lines = open(path).read().splitlines()
    start = lines.index("endheader") + 1
    labels = lines[start].split("\t")
    rows = [[float(c) for c in l.split("\t")] for l in lines[start + 1:] if l]
    return {lab: [r[i] for r in rows] for i, lab in enumerate(labels) if keep(lab)}

activation = lambda lab: lab.endswith("/activation")
control = lambda lab: lab.startswith("/forceset/")
sources = {  # figure -> the files (and columns) drawn in its muscle panels
    "open_loop_activations.png": [("plan.sto", activation), ("simulation.sto", activation), ("plan_controls.sto", control)],
    "rh_activations.png": [("simulation.sto", activation), ("simulation_controls.sto", control)],
    "forward_states.png": [("states.sto", activation), ("controls.sto", control)],
}
bad, checked = [], 0
for line in open(sys.argv[1]):
    report = json.loads(line)
    folder, name = os.path.split(report["figure"])
    if name not in sources:
        continue
    checked += 1
    data = {}
    for file, keep in sources[name]:
        data.update({(file, lab): v for lab, v in columns(os.path.join(folder, file), keep).items()})
    values = [x for v in data.values() for x in v]
    low, high = min(values), max(values)
    muscles = {lab.split("/")[2] for file, lab in data if lab.endswith("/activation")}
    ylims = report["activation_ylims"]
    if set(ylims) != muscles:
        bad.append("%s: panels %s, muscles %s" % (report["figure"], sorted(ylims), sorted(muscles)))
        continue
    limits = {tuple(v) for v in ylims.values()}
    if len(limits) != 1:
        bad.append("%s: panels do not share the y limits: %s" % (report["figure"], ylims))
        continue
    bottom, top = limits.pop()
    if bottom > min(low, 0) or (low >= 0 and bottom != 0):
        bad.append("%s: y from %g, data from %g" % (report["figure"], bottom, low))
    if top < high or top < 0.1 or top > max(0.1, 3 * high):
        bad.append("%s: y up to %g, data up to %g" % (report["figure"], top, high))
if checked != 7:
    bad.append("scales reported for %d activation figures, want 7" % checked)
for b in bad:
    print("FAILED:", b)
sys.exit(1 if bad else 0)
EOF

# Errors: usage, missing paths, nothing to plot, malformed files (named), partial output kept apart.
expect 0 "Usage: plot_results.py" -- "${plot[@]}" --help
expect 2 "Usage" -- "${plot[@]}"
expect 2 "unknown option '--bogus'" -- "${plot[@]}" --bogus "$tmp/elbow_1dof"
expect 1 "$tmp/nowhere: no such folder" -- "${plot[@]}" "$tmp/nowhere"
mkdir -p "$tmp/empty/sub"
expect 1 "$tmp/empty: no program output" -- "${plot[@]}" "$tmp/empty"
cp -r "$tmp/elbow_1dof/open_loop" "$tmp/bad_cell"
sed -i '$s/^[^\t]*\t/x\t/' "$tmp/bad_cell/simulation.sto"
expect 1 "$tmp/bad_cell/simulation.sto: line" -- "${plot[@]}" "$tmp/bad_cell"
cp -r "$tmp/elbow_1dof/forward" "$tmp/truncated"
sed -i '$d' "$tmp/truncated/states.sto"
expect 1 "$tmp/truncated/states.sto: header says nRows" -- "${plot[@]}" "$tmp/truncated"
cp -r "$tmp/elbow_1dof/receding_horizon" "$tmp/no_header"
sed -i '/^endheader$/d' "$tmp/no_header/predictions/step_0003.sto"
expect 1 "$tmp/no_header/predictions/step_0003.sto: not an OpenSim storage file" -- "${plot[@]}" "$tmp/no_header"
cp -r "$tmp/elbow_1dof/open_loop" "$tmp/bad_summary"
printf '{"inputs": ' > "$tmp/bad_summary/summary.json"
expect 1 "$tmp/bad_summary/summary.json: cannot read JSON" -- "${plot[@]}" "$tmp/bad_summary"
# A bad folder among good ones: the good ones are still drawn, the exit code says 1.
expect 1 "wrote $tmp/elbow_1dof/forward/forward_states.png" -- "${plot[@]}" "$tmp/truncated" "$tmp/elbow_1dof/forward"
exit $fail
