#!/usr/bin/env python3
"""Long runs of the receding-horizon program on the paper's arm and the seated knee: a new set
point every 2 s (drawn within the middle 80 % of each joint's range, [30, 100] deg where it has
none; seed 1), the rows streamed to file and no per-step history kept (--no-predictions). Runs
60 s and 600 s of simulated time, each in a process of its own, and compares their control
steps' 99th percentile and their peak resident memory. Prints one JSON record; with --previous,
each number beside the previous record's.

    /usr/bin/python3 bench/long_run_bench.py --program build/bin/flatsos --out record.json
"""
import argparse
import json
import math
import os
import pathlib
import platform
import random
import subprocess
import sys
import tempfile
import time


ROOT = pathlib.Path(__file__).resolve().parents[1]
MODELS = {"arm": ROOT / "models" / "arm_richter_warner.json", "knee": ROOT / "models" / "seated_knee_r.json"}


def joint_ranges_deg(model_file):
    """{joint name: (lowest, highest) set point, deg}: the middle 80 % of its range, or [30, 100]."""
    out = {}
    for joint in json.loads(model_file.read_text())["joints"]:
        lo, hi = (math.degrees(x) for x in joint.get("range_rad", (math.radians(30), math.radians(100))))
        if "range_rad" in joint:
            lo, hi = lo + 0.1 * (hi - lo), hi - 0.1 * (hi - lo)
        out[joint["name"]] = (lo, hi)
    return out


def write_setpoints(path, model_file, duration_s, seed=1):
    rng = random.Random(seed)
    ranges = joint_ranges_deg(model_file)
    rows = [[t] + [rng.uniform(lo, hi) for lo, hi in ranges.values()] for t in range(2, int(duration_s), 2)]
    header = f"setpoints\nversion=1\nnRows={len(rows)}\nnColumns={1 + len(ranges)}\ninDegrees=yes\nendheader\n"
    path.write_text(header + "\t".join(["time", *ranges]) + "\n" + "".join("\t".join(map(str, r)) + "\n" for r in rows))


def run(program, model_file, duration_s, folder):
    """The program's summary and its peak resident memory (MB) for one run of duration_s."""
    setpoints = folder / f"setpoints_{model_file.stem}_{duration_s}.sto"
    write_setpoints(setpoints, model_file, duration_s)
    out = folder / f"run_{model_file.stem}_{duration_s}"
    process = subprocess.Popen([program, "control", "--model", str(model_file), "--duration-s", str(duration_s),
                                "--setpoints", str(setpoints), "--no-predictions", "--out", str(out)],
                               stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(process.pid, 0)
    summary = json.loads((out / "summary.json").read_text())
    if os.waitstatus_to_exitcode(status) not in (0, 1):  # 1: the task failed, and the summary says why
        sys.exit(f"the {duration_s} s run ended with {os.waitstatus_to_exitcode(status)}: {summary['message']}")
    return summary, usage.ru_maxrss / 1024.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--program", default="build/bin/flatsos", help="the flatsos command")
    parser.add_argument("--out", help="also write the record here")
    parser.add_argument("--previous", help="a previous record, to print beside this one")
    args = parser.parse_args()
    record = {"date": time.strftime("%Y-%m-%d"), "machine": platform.processor() or platform.machine(), "models": {}}
    with tempfile.TemporaryDirectory() as folder:
        for name, model_file in MODELS.items():
            runs = {}
            for duration_s in (60, 600):
                summary, peak_MB = run(args.program, model_file, duration_s, pathlib.Path(folder))
                steps = summary["control_step_seconds"]
                runs[str(duration_s)] = {
                    "peak_resident_MB": round(peak_MB, 2), "step_p99_ms": round(1e3 * steps["p99"], 4),
                    "step_median_ms": round(1e3 * steps["median"], 4), "step_max_ms": round(1e3 * steps["max"], 3),
                    "real_time_factor": round(summary["real_time_factor"], 1),
                    "set_points_missed": sum(s is None for s in summary["setpoint_settling_s"][:-1]),
                    "faults": sum(summary["faults"].values()), "plan_failures": summary["plan_failures"],
                    "success": summary["success"], "message": summary["message"]}
            short, long = runs["60"], runs["600"]
            runs["p99_ratio_600_to_60"] = round(long["step_p99_ms"] / short["step_p99_ms"], 3)
            runs["peak_resident_growth_MB"] = round(long["peak_resident_MB"] - short["peak_resident_MB"], 2)
            record["models"][name] = runs
    previous = json.loads(pathlib.Path(args.previous).read_text()) if args.previous else None
    print(json.dumps({"now": record, "previous": previous} if previous else record, indent=1))
    if args.out:
        pathlib.Path(args.out).write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
