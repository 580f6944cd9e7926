"""The closed loop with noisy, late measurements, compute deadlines and changing set points, from
Python as from the program (flatsos.run_receding_horizon's real-time keywords)."""
import json
import subprocess

import numpy as np

import flatsos


def test_noise_and_delays_give_the_programs_run_for_the_same_seed(arm, build_dir, models_dir, tmp_path):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0,
                                       noise_deg=0.2, noise_deg_per_s=2.0, measurement_delay=0.01,
                                       actuation_delay=0.02, seed=5)
    program = subprocess.run([str(build_dir / "bin" / "arm_receding_horizon"), "--noise-deg", "0.2",
                              "--noise-deg-per-s", "2", "--measurement-delay-s", "0.01", "--actuation-delay-s",
                              "0.02", "--seed", "5", "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert run["success"] and summary["success"]
    assert run["settling_time"] == summary["settling_time_s"]
    assert np.degrees(np.abs(run["q"][-1] - np.radians(summary["final_q_deg"])).max()) < 1e-9
    assert summary["sensors"] == {"noise_deg": 0.2, "noise_deg_per_s": 2.0, "measurement_delay_s": 0.01,
                                  "actuation_delay_s": 0.02, "seed": 5}
    # The actuation delay reaches the plant: without it, another run.
    on_time = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0, noise_deg=0.2,
                                           noise_deg_per_s=2.0, measurement_delay=0.01, seed=5)
    assert np.abs(on_time["q"][-1] - run["q"][-1]).max() > 1e-9
    # Another seed is another run: the noise reaches the plan.
    other = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0,
                                         noise_deg=0.2, noise_deg_per_s=2.0, measurement_delay=0.01, seed=6)
    assert np.abs(other["q"][-1] - run["q"][-1]).max() > 1e-9


def test_injected_deadline_misses_are_counted_and_the_loop_holds(arm):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0,
                                       inject_deadline_misses=0.2, seed=2)
    assert run["success"], run["message"]
    assert 0 < run["deadline_misses"] == run["faults"]["deadline_misses"] < run["steps"]
    assert run["fallbacks"] <= run["deadline_misses"] and run["longest_deadline_miss_run"] >= 1
    assert run["faults"]["solver_failures"] == 0 and run["worst_step_seconds"] > 0.0


def test_a_deadline_no_plan_meets_is_a_failed_task_that_says_so(arm):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 1.0, deadline=1e-9)
    assert not run["success"]
    assert "missed their compute deadline" in run["message"]
    assert run["faults"]["steps_without_plan"] == run["steps"]


def test_set_points_are_each_reached(arm):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 3.0,
                                       setpoints=[(1.5, np.radians([40, 60]))])
    assert run["success"], run["message"]
    assert len(run["setpoint_settling"]) == 2 and all(s is not None for s in run["setpoint_settling"])
    assert np.degrees(np.abs(run["q"][-1] - np.radians([40, 60])).max()) < 1.0
    assert np.degrees(np.abs(run["q"][run["time"] <= 1.5][-1] - np.radians([80, 80])).max()) < 1.0


SETPOINTS_STO = "setpoints\nversion=1\nnRows=1\nnColumns={columns}\ninDegrees=yes\nendheader\n{header}\n{row}\n"


def test_the_programs_set_points_file_is_pythons_setpoints(arm, build_dir, tmp_path):
    model, _ = arm
    (tmp_path / "sp.sto").write_text(SETPOINTS_STO.format(columns=3, header="time\tshoulder\telbow", row="1.5\t40\t60"))
    program = subprocess.run([str(build_dir / "bin" / "arm_receding_horizon"), "--setpoints", str(tmp_path / "sp.sto"),
                              "--duration-s", "3", "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 3.0,
                                       setpoints=[(1.5, np.radians([40, 60]))])
    assert summary["setpoint_settling_s"] == run["setpoint_settling"]
    assert np.degrees(np.abs(run["q"][-1] - np.radians(summary["final_q_deg"])).max()) < 1e-9
    # A joint without a column is named, nothing is run.
    (tmp_path / "one.sto").write_text(SETPOINTS_STO.format(columns=2, header="time\tshoulder", row="1.5\t40"))
    refused = subprocess.run([str(build_dir / "bin" / "arm_receding_horizon"), "--setpoints", str(tmp_path / "one.sto"),
                              "--out", str(tmp_path / "refused")], capture_output=True, text=True)
    assert refused.returncode == 1 and "no column for joint 'elbow'" in refused.stderr
    assert not (tmp_path / "refused").exists()


def test_quick_arrival_gives_the_programs_run_and_a_bad_fraction_is_named(arm, build_dir, tmp_path):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0, quick_arrival=0.5)
    program = subprocess.run([str(build_dir / "bin" / "arm_receding_horizon"), "--quick-arrival", "0.5",
                              "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert run["success"] and run["settling_time"] == summary["settling_time_s"]
    assert summary["quick_arrival_fraction"] == 0.5
    assert np.degrees(np.abs(run["q"][-1] - np.radians(summary["final_q_deg"])).max()) < 1e-9
    whole = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 2.0, quick_arrival=1.0)
    assert run["settling_time"] < whole["settling_time"] - 0.1  # the second half of the move is quicker
    for fraction in (0.0, 1.5):
        try:
            flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 0.1, quick_arrival=fraction)
        except ValueError as e:
            assert "quick_arrival" in str(e)
        else:
            raise AssertionError(f"accepted quick_arrival={fraction}")
