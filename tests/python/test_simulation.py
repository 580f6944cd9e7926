"""flatsos.simulate_plan: what the C++ program simulates from the same inputs, and the plan."""
import subprocess

import numpy as np
import pytest

import flatsos
from flatsos.sto import joint_angles, muscle_activations, read_sto


@pytest.mark.parametrize("name, model_file", [("arm", "arm_richter_warner.json"), ("knee", "seated_knee_r.json")])
def test_the_simulation_is_the_cpp_programs_and_follows_the_plan(name, model_file, request, build_dir, models_dir,
                                                                  tmp_path):
    model, scenario = request.getfixturevalue(name)
    plan = scenario.plan(model)
    sim = flatsos.simulate_plan(plan)
    assert sim["finite"] and sim["message"] == ""
    assert sim["integrator"] == "rkm"  # chosen ("auto"): these muscles are not stiff at rest, as the program's
    assert sim["q"].shape == (301, len(model.joints)) and sim["activation"].shape == (301, len(model.muscles))
    program = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--model", str(models_dir / model_file),
                              "--paper", "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    table = read_sto(tmp_path / "simulation.sto")
    time, q = joint_angles(model, table)
    np.testing.assert_allclose(sim["time"], time, atol=1e-12)
    assert np.degrees(np.abs(sim["q"] - q).max()) < 1e-9
    assert np.abs(sim["activation"] - muscle_activations(model, table)).max() < 1e-9
    # Planned vs simulated (measured: 1.7e-7 deg, activations 6e-10).
    planned = plan.sample(sim["time"])
    assert np.degrees(np.abs(planned["q"] - sim["q"]).max()) < 1e-5
    assert np.abs(planned["activation"] - sim["activation"]).max() < 1e-6


def test_other_integrators_and_bad_options(arm):
    model, scenario = arm
    plan = scenario.plan(model)
    bdf = flatsos.simulate_plan(plan, integrator="bdf", accuracy=1e-8, reports=30)
    assert bdf["q"].shape == (31, 2) and bdf["integrator"] == "bdf"
    np.testing.assert_allclose(bdf["q"][-1], scenario.target, atol=np.radians(0.05))
    with pytest.raises(ValueError, match="unknown integrator 'euler'"):
        flatsos.simulate_plan(plan, integrator="euler")
    with pytest.raises(ValueError, match="accuracy"):
        flatsos.simulate_plan(plan, accuracy=0.5)
    with pytest.raises(ValueError, match="reports"):
        flatsos.simulate_plan(plan, reports=0)
    with pytest.raises(ValueError, match="max_steps"):
        flatsos.simulate_plan(plan, max_steps=-1)
    # Stopped at the step limit, exactly: the report rows so far, a last row where it stopped,
    # the reason, not completed.
    stopped = flatsos.simulate_plan(plan, max_steps=100)
    assert stopped["step_limit_reached"] and stopped["finite"] and not stopped["completed"]
    assert "the step limit" in stopped["message"] and stopped["integrator_steps"] == 100
    assert 1 < len(stopped["time"]) < 301 and stopped["q"].shape == (len(stopped["time"]), 2)
    full = flatsos.simulate_plan(plan)
    assert full["completed"] and not full["step_limit_reached"]
    reported = len(stopped["time"]) - 1
    np.testing.assert_array_equal(stopped["q"][:reported], full["q"][:reported])
    assert full["time"][reported - 1] < stopped["time"][-1] < full["time"][reported]
    infeasible = scenario.plan(model, torque_pieces=1, torque_degree=0)
    with pytest.raises(ValueError, match="nothing to simulate"):
        flatsos.simulate_plan(infeasible)
