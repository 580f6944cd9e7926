"""flatsos.Model and flatsos.plan_open_loop against the C++ program on the same inputs, the
plan's samples against its boundary conditions and bounds, and every error path."""
import json
import subprocess

import numpy as np
import pytest

import flatsos


def test_a_model_names_its_joints_and_muscles_in_model_order(arm, knee):
    model, _ = arm
    assert model.joints == ["shoulder", "elbow"]
    assert model.muscles == ["anterior_deltoid", "posterior_deltoid", "biceps", "triceps_long", "triceps_short",
                             "brachialis"]
    # The file's flat outputs: E's rows, with the weights the file gives each muscle.
    E = model.flat_outputs
    described = json.loads(model.to_json())["flat_outputs"]
    assert E.shape == (4, 6)
    for row, output in zip(E, described):
        np.testing.assert_array_equal(row, [output["weights"].get(m, 0.0) for m in model.muscles])
    knee_model, _ = knee
    assert knee_model.joints == ["walker_knee_r"]  # OpenSim's joint (its coordinate: knee_angle_r)
    assert len(knee_model.muscles) == 13 and knee_model.flat_outputs.shape == (12, 13)  # chosen by the library


@pytest.mark.parametrize("name", ["arm", "knee"])
def test_the_plan_costs_what_the_cpp_program_plans(name, request, build_dir, models_dir, tmp_path):
    model, scenario = request.getfixturevalue(name)
    model_file = {"arm": "arm_richter_warner.json", "knee": "seated_knee_r.json"}[name]
    plan = scenario.plan(model)
    assert plan.status == "solved", plan.message
    program = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--model", str(models_dir / model_file),
                              "--paper", "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert plan.cost == pytest.approx(summary["cost_Ns"], rel=1e-9)
    # The cost's unit follows the effort: the arm's given flat outputs weigh tendon forces (N s),
    # the knee's, chosen by the library, normalized ones (s).
    assert plan.cost_unit == summary["cost_unit"] == {"arm": "N s", "knee": "s"}[name]


def test_samples_start_at_the_initial_state_end_at_the_target_and_keep_every_bound(arm):
    model, scenario = arm
    plan = scenario.plan(model)
    times = np.linspace(0.0, scenario.duration, 301)
    s = plan.sample(times)
    assert set(s) == {"time", "q", "activation", "excitation", "tendon_force"}
    assert s["q"].shape == (301, 2) and s["activation"].shape == (301, 6)
    np.testing.assert_allclose(s["time"], times)
    np.testing.assert_allclose(s["q"][0], scenario.q0, atol=1e-12)
    np.testing.assert_allclose(s["q"][-1], scenario.target, atol=1e-9)
    np.testing.assert_allclose(s["activation"][0], scenario.a0, atol=1e-9)
    assert s["excitation"].min() >= -1e-6 and s["excitation"].max() <= 1.0 + 1e-6
    assert s["activation"].min() > 0.0 and s["activation"].max() <= 1.0 + 1e-6
    assert s["tendon_force"].min() >= scenario.reserves - 1e-6


def test_the_whole_program_nlp_plans_what_the_exchange_plans(arm):
    model, scenario = arm
    exchange = scenario.plan(model, bounds=False)
    nlp = scenario.plan(model, bounds=False, method="whole_program_nlp")
    assert exchange.status == "solved" and nlp.status == "solved", nlp.message
    assert exchange.sos["method"] == "exchange" and nlp.sos["method"] == "whole_program_nlp"
    assert nlp.cost == pytest.approx(exchange.cost, rel=1e-6)
    assert nlp.sos["certified"] and nlp.sos["exchange_rounds"] == 0
    assert nlp.sos["nlp_variables"] > nlp.sos["nlp_equalities"] > 0
    assert 0.0 <= nlp.sos["max_certificate_residual"] <= 1e-9
    assert "nlp_variables" not in exchange.sos
    with pytest.raises(ValueError, match="method: .*'sdp'.*expected 'exchange' or 'whole_program_nlp'"):
        scenario.plan(model, method="sdp")


def test_an_infeasible_plan_says_so_and_has_no_cost_or_samples(arm):
    model, scenario = arm
    # The paper's single torque box: at t = 0 the initial state fixes Y and the box's half-width
    # costs the anterior deltoid more guaranteed force than it has.
    plan = scenario.plan(model, torque_pieces=1, torque_degree=0)
    assert plan.status == "infeasible"
    assert plan.message
    assert plan.cost is None
    with pytest.raises(ValueError, match="infeasible"):
        plan.sample([0.0])


def test_without_initial_activations_the_plan_starts_from_the_minimum_effort_rest(arm):
    model, scenario = arm
    plan = flatsos.plan_open_loop(model, scenario.q0, [0.0, 0.0], None, scenario.target, scenario.duration, 10.0)
    assert plan.status == "solved", plan.message
    assert plan.cost > 0.0


@pytest.mark.parametrize("field, change, words", [
    ("q0", {"q0": [0.0]}, "q0: expected 2 numbers, got 1"),
    ("qd0", {"qd0": "fast"}, "qd0: expected 2 numbers"),
    ("a0", {"a0": [0.5] * 5}, "a0: expected 6 numbers, got 5"),
    ("a0", {"a0": [0.0] * 6}, "a0: activations must lie in (0, 1]"),
    ("target", {"target": 1.0}, "target: expected 2 numbers, got one number"),
    ("duration", {"duration": -3.0}, "duration: must be a positive number"),
    ("duration", {"duration": float("nan")}, "duration: must be a positive number"),
    ("reserves", {"reserves": [1.0, 2.0]}, "reserves: expected 6 numbers or one number, got 2"),
    ("reserves", {"reserves": -1.0}, "reserve"),
])
def test_bad_input_raises_a_value_error_naming_the_field(arm, field, change, words):
    model, scenario = arm
    args = dict(q0=scenario.q0, qd0=scenario.qd0, a0=scenario.a0, target=scenario.target, duration=scenario.duration,
                reserves=scenario.reserves)
    args.update(change)
    with pytest.raises(ValueError) as error:
        flatsos.plan_open_loop(model, **args)
    assert words in str(error.value)


def test_a_bad_model_file_or_sample_time_raises_a_value_error(arm, tmp_path):
    with pytest.raises(ValueError, match="cannot be opened"):
        flatsos.Model(str(tmp_path / "missing.json"))
    broken = tmp_path / "broken.json"
    broken.write_text("{ not json")
    with pytest.raises(ValueError, match="broken.json"):
        flatsos.Model(str(broken))
    model, scenario = arm
    plan = scenario.plan(model)
    with pytest.raises(ValueError, match="outside the plan's"):
        plan.sample([scenario.duration + 0.1])


def test_the_shortest_transfer_matches_the_cpp_program_and_its_bracket(arm, build_dir, tmp_path):
    model, s = arm
    r = flatsos.shortest_transfer(model, s.q0, s.qd0, s.a0, s.target, s.reserves, longest=3.0, preset="paper")
    assert r["status"] == "solved", r["message"]
    assert r["below_status"] == "infeasible" and 0 < r["shortest"] - r["no_plan_below"] <= 1e-3
    assert r["plan"].status == "solved" and r["plan"].duration == pytest.approx(r["shortest"], abs=1e-12)
    assert r["tried"][0]["duration"] == 3.0 and len(r["tried"]) > 2
    # Its ends, planned again one by one.
    at = flatsos.plan_open_loop(model, s.q0, s.qd0, s.a0, s.target, r["shortest"], s.reserves, preset="paper")
    below = flatsos.plan_open_loop(model, s.q0, s.qd0, s.a0, s.target, r["no_plan_below"], s.reserves, preset="paper")
    assert at.status == "solved" and at.cost == pytest.approx(r["plan"].cost, rel=1e-9)
    assert below.status == "infeasible"
    program = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--shortest-time", "--paper", "--duration-s", "3",
                              "--out", str(tmp_path)], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    summary = json.loads((tmp_path / "summary.json").read_text())["shortest_transfer"]
    assert summary["shortest_duration_s"] == pytest.approx(r["shortest"], abs=1e-12)


def test_the_shortest_transfer_names_bad_options_and_reports_no_plan(arm):
    model, s = arm
    with pytest.raises(ValueError, match="scan_ratio"):
        flatsos.shortest_transfer(model, s.q0, s.qd0, s.a0, s.target, s.reserves, longest=3.0, ratio=1.0)
    with pytest.raises(ValueError, match="lower_s"):
        flatsos.shortest_transfer(model, s.q0, s.qd0, s.a0, s.target, s.reserves, longest=3.0, shortest=-1.0)
    none = flatsos.shortest_transfer(model, s.q0, s.qd0, s.a0, s.target, s.reserves, longest=1.0, preset="paper")
    assert none["status"] == "infeasible" and none["shortest"] is None and none["plan"].status == "infeasible"
    assert "no plan at the longest duration" in none["message"]


def test_graded_spans_reach_the_planner_and_come_back_in_the_plan(arm):
    model, scenario = arm
    # Spans (and torque pieces) that grow by 1.06 from the start: short ones where the transfer is
    # fast. The plan reports the breakpoints it used; growth 1 keeps them uniform.
    graded = scenario.plan(model, flat_output_degree=5, flat_output_spans=12, flat_output_span_growth=1.25,
                           torque_pieces=12, torque_piece_growth=1.25)
    assert graded.status == "solved", graded.message
    breaks = np.asarray(graded.sos["flat_output_breakpoints"])
    assert len(breaks) == 13 and breaks[0] == 0.0 and breaks[-1] == pytest.approx(scenario.duration)
    assert np.diff(breaks)[1:] / np.diff(breaks)[:-1] == pytest.approx(np.full(11, 1.25))
    starts = np.asarray(graded.sos["torque_piece_starts"])
    assert len(starts) == 12 and starts[0] == 0.0
    assert np.diff(starts)[1:] / np.diff(starts)[:-1] == pytest.approx(np.full(10, 1.25))
    uniform = scenario.plan(model, flat_output_degree=5, flat_output_spans=12)
    assert np.diff(uniform.sos["flat_output_breakpoints"]) == pytest.approx(np.full(12, scenario.duration / 12))
    assert graded.cost != pytest.approx(uniform.cost, rel=1e-6)
    with pytest.raises(ValueError, match="flat_output_span_growth"):
        scenario.plan(model, flat_output_spans=12, flat_output_span_growth=-1.0)  # 0: automatic
    with pytest.raises(ValueError, match="piece_growth"):
        scenario.plan(model, torque_piece_growth=float("nan"))


def _squared_excitation_integral(plan, duration, points=3001):
    """Simpson's rule of sum_j n_j^2 over the plan's samples."""
    times = np.linspace(0.0, duration, points)
    f = (plan.sample(times)["excitation"] ** 2).sum(axis=1)
    h = times[1] - times[0]
    return h / 3.0 * (f[0] + f[-1] + 4.0 * f[1:-1:2].sum() + 2.0 * f[2:-1:2].sum())


def test_a_squared_excitation_plan_minimizes_what_it_reports(arm):
    model, scenario = arm
    squared = scenario.plan(model, preset="best", effort="excitation_squared")
    linear = scenario.plan(model, preset="best")
    assert squared.status == "solved" and linear.status == "solved", squared.message + linear.message
    assert squared.effort == "excitation_squared" and squared.cost_unit == "s"
    assert linear.effort == "tendon_force"
    # The reported cost is the integral of the plan's own squared excitations, and below what the
    # linear plan's excitations cost under the same effort (measured: 0.2349 against 0.2383 s).
    assert squared.cost == pytest.approx(_squared_excitation_integral(squared, scenario.duration), rel=1e-3)
    assert squared.cost < 0.995 * _squared_excitation_integral(linear, scenario.duration)
    assert "excitation_squared" in repr(squared)
    # "paper" is the model's own linear effort, as None is.
    assert scenario.plan(model, effort="paper").cost == pytest.approx(scenario.plan(model).cost, rel=1e-12)


@pytest.mark.parametrize("kwargs, words", [
    ({"effort": "excitations_squared"}, "excitation_squared"),
    ({"effort": 2}, "effort: expected"),
    ({"effort": "paper", "weights": [1.0] * 6}, "weights"),
    ({"effort": "activation_squared", "weights": [1.0, 2.0]}, "weights"),
])
def test_a_bad_effort_raises_a_value_error_naming_it(arm, kwargs, words):
    model, scenario = arm
    with pytest.raises(ValueError, match=words):
        scenario.plan(model, **kwargs)
