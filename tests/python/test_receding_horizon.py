"""flatsos.run_receding_horizon against the C++ program on the same inputs, on a plant with other
muscles, and every error path; Model.with_strength against a model file with those forces."""
import json
import subprocess

import numpy as np
import pytest

import flatsos
from flatsos.sto import joint_angles, muscle_activations, read_sto

MODEL_FILES = {"arm": "arm_richter_warner.json", "knee": "seated_knee_r.json"}


def receding_horizon_scenario(model_file):
    s = json.loads(model_file.read_text())["scenarios"]["receding_horizon"]
    return np.radians(s["q0_deg"]), np.radians(s["target_deg"]), s["duration_s"], s["reserves_N"]


@pytest.mark.parametrize("name", ["arm", "knee"])
def test_the_closed_loop_is_the_cpp_programs(name, request, build_dir, models_dir, tmp_path):
    model, _ = request.getfixturevalue(name)
    model_file = models_dir / MODEL_FILES[name]
    q0, target, duration, reserves = receding_horizon_scenario(model_file)
    run = flatsos.run_receding_horizon(model, q0, target, duration, reserves=reserves)
    assert run["success"] and run["message"] == "" and run["finite"], run["message"]
    assert run["plan_failures"] == 0 and run["steps"] == round(duration / 0.05)
    rows = run["steps"] * 5 + 1  # the loop's five reports per period, and the start
    assert run["q"].shape == (rows, len(model.joints)) and run["activation"].shape == (rows, len(model.muscles))
    assert run["excitation"].shape == run["activation"].shape
    assert run["real_time_factor"] > 0.0
    program = subprocess.run([str(build_dir / "bin" / "arm_receding_horizon"), "--model", str(model_file),
                              "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert run["settling_time"] == pytest.approx(summary["settling_time_s"], abs=1e-12)
    assert summary["steps"] == run["steps"] and summary["excitation_bounds"]["bounded_steps"] == run["bounded_steps"]
    states, controls = read_sto(tmp_path / "simulation.sto"), read_sto(tmp_path / "simulation_controls.sto")
    time, q = joint_angles(model, states)
    np.testing.assert_allclose(run["time"], time, atol=1e-12)
    assert np.degrees(np.abs(run["q"] - q).max()) < 1e-9
    assert np.abs(run["activation"] - muscle_activations(model, states)).max() < 1e-9
    excitation = np.column_stack([controls[f"/forceset/{muscle}"] for muscle in model.muscles])
    assert np.abs(run["excitation"] - excitation).max() < 1e-9
    # It settles where the program says, and stays there.
    settled = run["time"] >= run["settling_time"]
    assert np.degrees(np.abs(run["q"][settled] - target).max()) <= 1.0
    assert np.degrees(np.abs(run["q"][run["time"] < run["settling_time"]][-1] - target).max()) > 1.0


def test_a_weaker_plant_is_driven_to_the_target_by_the_default_observer(arm, models_dir):
    model, _ = arm
    q0, target, _, _ = receding_horizon_scenario(models_dir / MODEL_FILES["arm"])
    weak = model.with_strength(0.8)
    kwargs = dict(plant=weak, integrator="bdf")
    nominal = flatsos.run_receding_horizon(model, q0, target, 2.0, integrator="bdf")
    mismatched = flatsos.run_receding_horizon(model, q0, target, 2.0, **kwargs)  # the default observer
    assert mismatched["success"], mismatched["message"]
    assert np.degrees(np.abs(mismatched["q"][-1] - target).max()) < 0.1
    # The paper's controller (no observer) ends degrees short of the target with the same plant.
    paper = flatsos.run_receding_horizon(model, q0, target, 2.0, observer_gain=0.0, **kwargs)
    assert not paper["success"] and np.degrees(np.abs(paper["q"][-1] - target).max()) > 5.0
    # The plant starts from its own muscles' rest (what a plan for it starts from), not the model's.
    rest = {m: flatsos.plan_open_loop(m, q0, [0, 0], None, target, 2.0, 1.0).sample([0.0])["activation"][0]
            for m in (model, weak)}
    np.testing.assert_allclose(mismatched["activation"][0], rest[weak], rtol=1e-9)
    np.testing.assert_allclose(nominal["activation"][0], rest[model], rtol=1e-9)
    assert np.abs(rest[weak] - rest[model]).max() > 0.01
    # The weaker plant needs more activation for the same motion.
    assert mismatched["activation"].sum() > 1.05 * nominal["activation"].sum()


def test_a_failed_task_says_why_and_is_not_a_success(arm):
    model, _ = arm
    run = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 0.1)
    assert not run["success"] and run["settling_time"] is None
    assert run["message"].startswith("never settled within 1 deg of the target in 0.1 s (final error")
    tight = flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 0.1,
                                         settle_tolerance=np.radians(0.5))
    assert tight["message"].startswith("never settled within 0.5 deg")


@pytest.mark.parametrize("kwargs, match", [
    (dict(q0=[0.1]), "q0: expected 2 numbers, got 1"),
    (dict(target="up"), "target: expected 2 numbers"),
    (dict(duration=-1.0), "duration"),
    (dict(reserves=[1.0, 2.0]), "reserves: expected 6 numbers or one number, got 2"),
    (dict(a0=[0.0] * 6), r"a0: activations must lie in \(0, 1\]"),
    (dict(qd0=[0.0]), "qd0: expected 2 numbers"),
    (dict(period=0.6), "the control period must not exceed the horizon"),
    (dict(period=0.0), "control period must be > 0 s"),
    (dict(solver="newton"), "solver: unknown SLP solver 'newton'"),
    (dict(integrator="euler"), "unknown integrator 'euler'"),
    (dict(accuracy=0.5), "accuracy"),
    (dict(grid_points=1), "need at least 2 grid points"),
    (dict(horizon=-0.5), "horizon"),
    (dict(observer_gain=-1.0), "observer gain must be a finite number >= 0"),
    (dict(settle_tolerance=0.0), "settle_tolerance"),
    (dict(plant="arm.json"), "plant: expected a flatsos.Model"),
    (dict(noise_deg=-0.1), "angle noise must be finite and >= 0"),
    (dict(noise_deg_per_s=float("nan")), "speed noise must be finite and >= 0"),
    (dict(measurement_delay=-0.01), "measurement delay must be finite and >= 0"),
    (dict(actuation_delay=-0.01), "actuation delay: must be a finite time >= 0 s"),
    (dict(deadline=-1.0), "deadline must be finite and >= 0 s"),
    (dict(inject_deadline_misses=1.5), "deadline-miss fraction must be in"),
    (dict(setpoints=[(1.0, [0.5])]), "setpoints target: expected 2 numbers"),
    (dict(setpoints=[(1.0, [0.5, 0.5]), (0.5, [0.6, 0.6])]), "set point 2: times must be finite and ascending"),
    (dict(setpoints=5), "setpoints: a sequence of"),
])
def test_bad_input_raises_a_value_error_naming_the_argument(arm, kwargs, match):
    model, _ = arm
    args = dict(q0=np.radians([20, 20]), target=np.radians([80, 80]), duration=0.5)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        flatsos.run_receding_horizon(model, **args)


def test_a_plant_of_another_model_is_refused(arm, knee):
    model, _ = arm
    with pytest.raises(ValueError, match="plant"):
        flatsos.run_receding_horizon(model, np.radians([20, 20]), np.radians([80, 80]), 0.5, plant=knee[0])


def test_with_strength_on_a_model_whose_flat_outputs_the_library_chose(knee, models_dir, tmp_path):
    model, scenario = knee
    factors = np.linspace(0.8, 1.2, len(model.muscles))
    data = json.loads((models_dir / MODEL_FILES["knee"]).read_text())
    for muscle, f in zip(data["muscles"], factors):
        muscle["max_isometric_force_N"] *= f
    (tmp_path / "scaled.json").write_text(json.dumps(data))
    # The file's model chooses its flat outputs again (the same: the choice scores moment arms);
    # its effort is the tendon forces over the new maximum forces.
    a, b = scenario.plan(model.with_strength(factors)), scenario.plan(flatsos.Model(str(tmp_path / "scaled.json")))
    assert a.status == b.status == "solved"
    assert a.cost == pytest.approx(b.cost, rel=1e-9)
    assert a.cost != pytest.approx(scenario.plan(model).cost, rel=1e-3)


def test_with_strength_is_the_model_file_with_those_forces(arm, models_dir, tmp_path):
    model, scenario = arm
    factors = np.array([0.8, 1.2, 0.9, 1.1, 1.0, 0.85])
    strong = model.with_strength(factors)
    np.testing.assert_allclose(strong.max_isometric_forces, model.max_isometric_forces * factors, rtol=1e-15)
    assert strong.joints == model.joints and strong.muscles == model.muscles
    data = json.loads((models_dir / MODEL_FILES["arm"]).read_text())
    for muscle, f in zip(data["muscles"], factors):
        muscle["max_isometric_force_N"] *= f
    (tmp_path / "scaled.json").write_text(json.dumps(data))
    from_file = flatsos.Model(str(tmp_path / "scaled.json"))
    # From each model's own minimum-effort rest (the scenario's activations balance only the
    # nominal forces).
    a, b, nominal = (flatsos.plan_open_loop(m, scenario.q0, [0, 0], None, scenario.target, scenario.duration,
                                            scenario.reserves) for m in (strong, from_file, model))
    assert a.status == b.status == nominal.status == "solved", a.message + b.message + nominal.message
    assert a.cost == pytest.approx(b.cost, rel=1e-12)
    times = np.linspace(0.0, scenario.duration, 61)
    sa, sb, sn = a.sample(times), b.sample(times), nominal.sample(times)
    np.testing.assert_allclose(sa["activation"], sb["activation"], atol=1e-12)
    # The effort is in tendon force, which the torques fix; strength shows in the activations.
    assert np.abs(sa["activation"] - sn["activation"]).max() > 0.01
    # Its text read back (what a study's workers get) is the same model.
    text = flatsos.Model.from_json(strong.to_json(), "strong")
    np.testing.assert_allclose(text.max_isometric_forces, strong.max_isometric_forces, rtol=1e-15)
    assert flatsos.plan_open_loop(text, scenario.q0, [0, 0], None, scenario.target, scenario.duration,
                                  scenario.reserves).cost == pytest.approx(a.cost, rel=1e-12)
    with pytest.raises(ValueError, match="strong"):
        flatsos.Model.from_json("{}", "strong")
    np.testing.assert_allclose(model.with_strength(1.1).max_isometric_forces, 1.1 * model.max_isometric_forces)
    for bad, match in [(0.0, "factors: must be positive"), ([1.0] * 5, "factors: expected 6 numbers"),
                       (float("nan"), "factors: must be positive")]:
        with pytest.raises(ValueError, match=match):
            model.with_strength(bad)
