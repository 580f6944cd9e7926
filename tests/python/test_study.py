"""flatsos.study: the Dask batch against the serial loop (1000 plans, the same table), the
cluster path seen from a second client, the table file read back, and every error path."""
import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest

import flatsos
import flatsos.study as study

# Every study here plans the paper's configuration (the tests' numbers, and 1000 plans in seconds).
PAPER = {"preset": "paper"}
OWN_REST = {"plan": {"a0": None, "qd0_deg_per_s": [0, 0], "options": PAPER}, "strength": {"low": 0.8, "high": 1.2}}


@pytest.fixture(scope="module")
def arm_file(models_dir):
    return str(models_dir / "arm_richter_warner.json")


def test_a_cluster_gives_the_serial_loops_table_and_a_second_client_sees_its_workers(arm_file):
    import distributed  # installed by scripts/install_deps.sh: a missing one fails here, not skips
    with study.local_cluster(2) as cluster:
        on_cluster = study.run(arm_file, OWN_REST, 1000, seed=7, scheduler=cluster.scheduler_address)
        with distributed.Client(cluster.scheduler_address) as second:
            workers = set(second.scheduler_info()["workers"])
            cached = second.run(study.cached_models)  # asked in each worker process
            second_trim = second.run(lambda: os.environ.get("MALLOC_TRIM_THRESHOLD_"))
    serial = study.run(arm_file, OWN_REST, 1000, seed=7, workers=0)
    a, b = on_cluster.table(), serial.table()
    assert len(workers) == 2 and set(cached) == workers and all(n == 1 for n in cached.values())
    assert set(second_trim.values()) == {str(64 * 2**20)}  # the workers' environment, as local_cluster sets it
    assert set(a["worker"]) == workers  # both workers planned
    assert set(b["worker"]) == {"serial"}
    for column in serial.study.columns():
        if column not in study.TIMING_COLUMNS:
            np.testing.assert_array_equal(a[column], b[column], err_msg=column)
    assert (a["status"] == "solved").all()
    assert on_cluster.summary["ran_on"] == f"scheduler {cluster.scheduler_address}"
    assert serial.summary["statuses"] == {"solved": 1000} and serial.summary["feasible_fraction"] == 1.0
    # The draws: every factor in [0.8, 1.2], spread over it, reproducible from the seed.
    strengths = np.column_stack([b[f"strength_{m}"] for m in serial.study.muscles])
    assert strengths.min() >= 0.8 and strengths.max() <= 1.2 and strengths.std() > 0.1
    assert (strengths == serial.study.draw(1000, 7)[0]).all() and (strengths != serial.study.draw(1000, 8)[0]).all()


def test_unperturbed_samples_cost_what_plan_open_loop_plans(arm, arm_file):
    model, scenario = arm
    result = study.run(arm_file, {"plan": {"options": PAPER}, "strength": {"low": 1.0, "high": 1.0}}, 3, workers=0)
    expected = scenario.plan(model)
    t = result.table()
    assert list(t["status"]) == ["solved"] * 3
    np.testing.assert_allclose(t["cost_Ns"], expected.cost, rtol=1e-12)
    peaks = expected.sample(np.linspace(0, scenario.duration, 301))
    np.testing.assert_allclose(t["peak_activation"], peaks["activation"].max(), rtol=1e-12)
    np.testing.assert_allclose(t["target_shoulder_deg"], 90.0)


def test_targets_drawn_in_their_box_and_the_table_file_read_back(arm_file, tmp_path):
    box = {"plan": {"a0": None, "qd0_deg_per_s": [0, 0], "options": PAPER}, "target_deg": {"low": [60, 0], "high": [90, 20]}}
    result = study.run(arm_file, box, 20, workers=0)
    t = result.table()
    assert 60 <= t["target_shoulder_deg"].min() and t["target_shoulder_deg"].max() <= 90
    assert 0 <= t["target_elbow_deg"].min() and t["target_elbow_deg"].max() <= 20
    assert len(set(t["cost_Ns"])) == 20  # each target its own plan
    result.write(tmp_path / "out")
    with open(tmp_path / "out" / "table.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [list(r) for r in rows[:1]] == [result.study.columns()]
    for row, original in zip(rows, result.rows):
        for column, value in original.items():
            assert (float(row[column]) == value or (np.isnan(value) and row[column] == "nan")) \
                if isinstance(value, float) else row[column] == str(value), column
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["samples"] == 20 and summary["statuses"] == result.summary["statuses"]
    assert not list((tmp_path / "out").glob("*.tmp"))


def test_a_sample_the_library_refuses_is_a_row_that_says_why(arm_file):
    result = study.run(arm_file, {"plan": {"options": {"torque_pieces": -1}}}, 2, workers=0)
    t = result.table()
    assert list(t["status"]) == ["failed", "failed"] and np.isnan(t["cost_Ns"]).all()
    assert t["message"][0].startswith("error: ") and "torque" in t["message"][0]


@pytest.mark.parametrize("description, match", [
    ([], "study: expected a JSON object"),
    ({"strenght": {}}, r"study: unknown field\(s\) \['strenght'\]"),
    ({"strength": {"low": 0.8}}, "strength: expected an object with 'low' and 'high'"),
    ({"strength": {"low": 1.2, "high": 0.8}}, "strength: low must not exceed high"),
    ({"strength": {"low": [0.8] * 5, "high": 1.2}}, "strength.low: expected 6 numbers or one number, got 5"),
    ({"target_deg": {"low": 0, "high": [1, 2]}}, "target_deg.low: expected 2 numbers"),
    ({"plan": {"q0": [0, 0]}}, r"plan: unknown field\(s\) \['q0'\]"),
    ({"plan": {"duration_s": -1}}, "plan.duration_s: must be a positive number"),
    ({"plan": {"a0": [0.1] * 3}}, "plan.a0: expected 6 numbers, got 3"),
    ({"plan": {"options": {"degree": 5}}}, r"plan.options: unknown field\(s\) \['degree'\]"),
    ({"plan": {"reserves_N": float("nan")}}, "plan.reserves_N: values must be finite"),
])
def test_a_bad_description_names_the_field(arm_file, description, match):
    with pytest.raises(ValueError, match=match):
        study.run(arm_file, description, 2, workers=0)


def test_bad_options_and_models(arm_file, tmp_path):
    with pytest.raises(ValueError, match="samples: must be a whole number >= 1"):
        study.run(arm_file, {}, 0, workers=0)
    with pytest.raises(ValueError, match="workers: must be a whole number >= 0"):
        study.run(arm_file, {}, 2, workers=-1)
    with pytest.raises(ValueError, match="block: must be a whole number >= 1"):
        study.run(arm_file, {}, 2, workers=0, block=0)
    with pytest.raises(ValueError, match="model: cannot read"):
        study.run(str(tmp_path / "none.json"), {}, 2, workers=0)
    (tmp_path / "bad.json").write_text("{")
    with pytest.raises(ValueError, match="is not JSON"):
        study.run(str(tmp_path / "bad.json"), {}, 2, workers=0)
    (tmp_path / "empty.json").write_text("{}")
    with pytest.raises(ValueError, match="empty.json"):  # the library's message, naming the file
        study.run(str(tmp_path / "empty.json"), {}, 2, workers=0)


def test_the_command_line(arm_file, tmp_path):
    env = dict(os.environ)
    command = [sys.executable, "-m", "flatsos.study"]
    shown = subprocess.run(command + ["--help"], capture_output=True, text=True, env=env)
    assert shown.returncode == 0 and "--scheduler" in shown.stdout
    (tmp_path / "study.json").write_text(json.dumps(OWN_REST))
    ran = subprocess.run(command + ["--model", arm_file, "--study", str(tmp_path / "study.json"), "--samples", "30",
                                    "--workers", "0", "--out", str(tmp_path / "out")], capture_output=True, text=True)
    assert ran.returncode == 0, ran.stderr
    assert "study: 30/30 plans" in ran.stderr and "30 plans on serial" in ran.stdout
    assert len((tmp_path / "out" / "table.csv").read_text().splitlines()) == 31
    (tmp_path / "bad.json").write_text(json.dumps({"strength": {"low": 2, "high": 1}}))
    refused = subprocess.run(command + ["--model", arm_file, "--study", str(tmp_path / "bad.json"), "--out",
                                        str(tmp_path / "refused")], capture_output=True, text=True)
    assert refused.returncode == 2
    assert refused.stderr.strip() == "flatsos.study: error: strength: low must not exceed high"
    assert not (tmp_path / "refused").exists()
    missing = subprocess.run(command + ["--model", arm_file, "--study", str(tmp_path / "none.json")],
                             capture_output=True, text=True)
    assert missing.returncode == 2 and "study: cannot read" in missing.stderr


def test_a_study_of_a_model_whose_flat_outputs_the_library_chooses(knee, models_dir):
    model, scenario = knee
    knee_file = str(models_dir / "seated_knee_r.json")
    result = study.run(knee_file, {"plan": {"options": PAPER}, "strength": {"low": 1.0, "high": 1.0}, "target_deg": {"low": [30], "high": [30]}},
                       2, workers=0)
    t = result.table()
    assert list(t["status"]) == ["solved", "solved"], t["message"]
    np.testing.assert_allclose(t["cost_Ns"], scenario.plan(model).cost, rtol=1e-12)
    weaker = study.run(knee_file, {"plan": {"options": PAPER}, "strength": {"low": 0.8, "high": 0.9}}, 3, workers=0).table()
    assert (weaker["status"] == "solved").all(), weaker["message"]
    # The library's effort here is tendon force over maximum force: each weight grows by 1/f >=
    # 1/0.9 (the start, each subject's own rest, moves too, so the cost need not grow as much).
    assert (weaker["cost_Ns"] > 1.03 * t["cost_Ns"][0]).all()


def _swing(path):
    """The paper's arm through a smooth 40 deg swing of both joints in 1 s (a coordinates table)."""
    t = np.linspace(0.0, 1.0, 101)
    s = t * t * (3.0 - 2.0 * t)
    rows = "\n".join(f"{a:.2f}\t{30 + 40 * b:.6f}\t{40 + 40 * b:.6f}" for a, b in zip(t, s))
    path.write_text("swing\nversion=1\ninDegrees=yes\nendheader\ntime\tshoulder\telbow\n" + rows + "\n")
    return str(path)


def test_a_tracking_study_runs_the_controller_on_each_samples_plant(arm, arm_file, tmp_path):
    arm, _ = arm
    motion = _swing(tmp_path / "swing.mot")
    description = {"track": {"coordinates": motion, "options": {"tolerance": np.radians(2.0)}},
                   "strength": {"low": 0.9, "high": 1.1}}
    serial = study.run(arm_file, description, 4, seed=3, workers=0)
    assert [row["status"] for row in serial.rows] == ["tracked"] * 4, [row["message"] for row in serial.rows]
    assert serial.summary["tracked_fraction"] == 1.0
    # Sample 0 is flatsos.track on a plant of that sample's strengths.
    factors = [serial.rows[0][f"strength_{name}"] for name in arm.muscles]
    direct = flatsos.track(arm, motion, plant=arm.with_strength(factors), tolerance=np.radians(2.0))
    assert np.allclose([serial.rows[0][f"rms_error_{j}_deg"] for j in ("shoulder", "elbow")],
                       np.degrees(direct["rms_error"]), rtol=1e-9)
    assert serial.rows[0]["excitation_squared_integral"] == pytest.approx(direct["excitation_squared_integral"], rel=1e-9)
    # Different plants track differently, all within a degree.
    rms = np.array([[row[f"rms_error_{j}_deg"] for j in ("shoulder", "elbow")] for row in serial.rows])
    assert np.all(rms < 1.0) and len(np.unique(rms[:, 1])) == 4
    # The same table from a Dask cluster.
    clustered = study.run(arm_file, description, 4, seed=3, workers=2, block=2)
    for column in serial.study.columns():
        if column not in study.TIMING_COLUMNS:
            assert [row[column] for row in clustered.rows] == [row[column] for row in serial.rows], column
    serial.write(tmp_path / "out")
    with open(tmp_path / "out" / "table.csv") as f:
        assert len(list(csv.DictReader(f))) == 4


def test_a_tracking_study_varies_the_effort(arm, arm_file, tmp_path):
    # The study's effort is the run's: null (the model's linear effort) gives flatsos.track's
    # effort=None run, which spends more than the default squared excitations.
    arm, _ = arm
    motion = _swing(tmp_path / "swing.mot")
    options = {"tolerance": np.radians(2.0), "effort": None}
    result = study.run(arm_file, {"track": {"coordinates": motion, "options": options}}, 1, seed=1, workers=0)
    assert result.rows[0]["status"] == "tracked", result.rows[0]["message"]
    linear = flatsos.track(arm, motion, effort=None, tolerance=np.radians(2.0))
    assert result.rows[0]["excitation_squared_integral"] == pytest.approx(linear["excitation_squared_integral"], rel=1e-9)
    squared = flatsos.track(arm, motion, tolerance=np.radians(2.0))
    assert squared["excitation_squared_integral"] < linear["excitation_squared_integral"]


def test_a_bad_tracking_description_names_the_field(arm_file, tmp_path):
    motion = _swing(tmp_path / "swing.mot")
    for description, match in [
            ({"track": {"coordinates": motion}, "plan": {}}, "track: a tracking study has no plan or target_deg"),
            ({"track": {}}, "track.coordinates: the motion file to follow is missing"),
            ({"track": {"coordinates": str(tmp_path / "none.mot")}}, "track.coordinates: no file"),
            ({"track": {"coordinates": motion, "options": {"horizon_s": 1}}}, "track.options: expected an object of"),
            ({"track": {"coordinates": motion, "speed": 1}}, r"track: unknown field\(s\) \['speed'\]"),
            ({"track": {"coordinates": motion, "options": {"tolerance": "2"}}}, "track.options.tolerance: expected a finite"),
            ({"track": {"coordinates": motion, "options": {"reserves": [1, None]}}}, "track.options.reserves"),
            ({"track": {"coordinates": motion, "options": {"effort": "squared"}}}, "track.options.effort: expected null or"),
            ({"track": {"coordinates": motion, "options": {"effort": ["x"]}}}, "track.options.effort: expected null or")]:
        with pytest.raises(ValueError, match=match):
            study.run(arm_file, description, 2, workers=0)


def test_a_plan_study_can_minimize_squared_excitations(arm, arm_file):
    # The effort reaches every sample's plan; its cost column says its unit (s, not N s).
    model, scenario = arm
    options = dict(PAPER, effort="excitation_squared")
    result = study.run(arm_file, {"plan": {"options": options}, "strength": {"low": 1.0, "high": 1.0}}, 1, workers=0)
    t = result.table()
    assert "cost_s" in result.study.columns() and "cost_Ns" not in result.study.columns()
    assert list(t["status"]) == ["solved"], list(t["message"])
    np.testing.assert_allclose(t["cost_s"], scenario.plan(model, effort="excitation_squared").cost, rtol=1e-12)
    assert "cost_s" in result.summary
    with pytest.raises(study.StudyError, match="plan.options.effort"):
        study.run(arm_file, {"plan": {"options": {"effort": "squared"}}}, 1, workers=0)
