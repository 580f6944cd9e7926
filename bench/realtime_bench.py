#!/usr/bin/env python3
"""The receding-horizon controller as a real limb runs it, on the paper's arm and the seated knee
(each model file's receding_horizon scenario, the product's defaults): measured with noise and
late, on a weaker and heavier plant, pushed by a torque pulse, and with plans that miss their
deadline. Prints one JSON record; with --previous, each number beside the previous record's.

    PYTHONPATH=build/python /usr/bin/python3 bench/realtime_bench.py --out record.json
"""
import argparse
import json
import pathlib
import platform
import sys
import time

import numpy as np

import flatsos

ROOT = pathlib.Path(__file__).resolve().parents[1]
MODELS = {"arm": ROOT / "models" / "arm_richter_warner.json", "knee": ROOT / "models" / "seated_knee_r.json"}
SENSORS = dict(noise_deg=0.2, noise_deg_per_s=2.0, measurement_delay=0.01, seed=1)


def heavier(path, factor):
    """The model file with every body's mass and inertia times `factor`."""
    description = json.loads(path.read_text())
    for body in description["bodies"]:
        body["mass_kg"] *= factor
        for key in ("inertia_about_mass_center_kg_m2", "principal_inertia_kg_m2", "product_inertia_kg_m2"):
            if key in body:
                body[key] = (np.asarray(body[key]) * factor).tolist()
    return flatsos.Model.from_json(json.dumps(description), source=f"{path.name} with masses x{factor}")


def error_deg(run, target):
    return np.degrees(np.abs(run["q"] - target).max(axis=1))


def back_within(run, target, after_s, tolerance_deg=1.0):
    """Seconds after `after_s` until the joints are within the tolerance and stay (None: never)."""
    outside = (run["time"] >= after_s) & (error_deg(run, target) > tolerance_deg)
    if outside[-1]:
        return None
    last = run["time"][outside].max() if outside.any() else after_s
    return float(max(0.0, last - after_s))


def row(run, target, **extra):
    settled = run["settling_time"]
    after = run["time"] >= (settled if settled is not None else np.inf)
    rms = float(np.sqrt(np.mean(np.degrees(run["q"][after] - target) ** 2))) if after.any() else None
    return dict(success=run["success"], settling_time_s=settled, rms_after_settling_deg=rms,
                final_error_deg=float(error_deg(run, target)[-1]), plan_failures=run["plan_failures"],
                deadline_misses=run["deadline_misses"], fallbacks=run["fallbacks"],
                worst_step_ms=1e3 * run["worst_step_seconds"], message=run["message"], **extra)


def scenario_rows(name):
    path = MODELS[name]
    model = flatsos.Model(str(path))
    s = json.loads(path.read_text())["scenarios"]["receding_horizon"]
    q0, target, reserves = np.radians(s["q0_deg"]), np.radians(s["target_deg"]), s["reserves_N"]
    duration = 3.0

    def run(**kw):
        return flatsos.run_receding_horizon(kw.pop("on", model), q0, target, kw.pop("duration", duration),
                                            reserves=reserves, **kw)

    out = {"noise_and_delay": row(run(**SENSORS), target)}
    plant = heavier(path, 1.2).with_strength(0.7)
    weak = run(plant=plant, **SENSORS)
    out["strength_0.7_masses_1.2_noise_and_delay"] = row(weak, target)
    # A 2 N m pulse on every joint for 100 ms at 1 s after the target was reached.
    pulse_s = 1.0 + (run()["settling_time"] or 0.0)
    joints = len(model.joints)
    pushed = run(disturbance=[(pulse_s, [2.0] * joints), (pulse_s + 0.1, [0.0] * joints)], duration=pulse_s + 1.5)
    out["pulse_2_N_m_100_ms"] = row(pushed, target, pulse_at_s=pulse_s,
                                    back_within_1_deg_after_pulse_s=back_within(pushed, target, pulse_s + 0.1))
    out["injected_deadline_misses_10_percent"] = row(run(inject_deadline_misses=0.1, seed=1), target)
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, help="write the record here (JSON)")
    parser.add_argument("--previous", type=pathlib.Path, help="a previous record to print beside")
    args = parser.parse_args()
    start = time.perf_counter()
    record = {"date": time.strftime("%Y-%m-%d"), "machine": platform.machine(),
              "rows": {name: scenario_rows(name) for name in MODELS}}
    record["wall_seconds"] = time.perf_counter() - start
    previous = json.loads(args.previous.read_text())["rows"] if args.previous else {}
    for name, rows in record["rows"].items():
        for case, values in rows.items():
            before = previous.get(name, {}).get(case, {})
            shown = {k: (v, before.get(k)) if before else v for k, v in values.items() if k != "message"}
            print(f"{name:5s} {case}: {json.dumps(shown)}")
            if values["message"]:
                print(f"      message: {values['message']}")
    if args.out:
        args.out.write_text(json.dumps(record, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
