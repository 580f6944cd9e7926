"""flatsos.animation and flatsos.sto: the stick figure against the arm's kinematics written out
here, the GIF frame by frame, the motion file's coordinates against the original .osim, and
every error path."""
import json
import math
import os
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest
from PIL import Image

import flatsos
import flatsos.animation as animation
import flatsos.sto as sto

OSIM = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "opensim" / "subject_walk_scaled.osim"


def test_the_arms_stick_figure_is_its_two_link_kinematics(arm):
    model, _ = arm
    skeleton = animation._Skeleton(model)
    for q1, q2 in [(0.0, 0.0), (0.3, 1.2), (-1.0, 2.5), (2.0, -0.4)]:
        (s0, e0), (s1, e1) = skeleton.segments(np.array([q1, q2]))
        elbow = 0.33 * np.array([math.cos(q1), math.sin(q1)])
        hand = elbow + 0.32 * np.array([math.cos(q1 + q2), math.sin(q1 + q2)])  # the forearm's length
        np.testing.assert_allclose(s0, [0, 0], atol=1e-12)
        np.testing.assert_allclose(e0, elbow, atol=1e-12)
        np.testing.assert_allclose(s1, elbow, atol=1e-12)
        np.testing.assert_allclose(e1, hand, atol=1e-12)
    origins, rotations = model.body_frames([0.3, 1.2])
    assert origins.shape == (2, 3) and rotations.shape == (2, 3, 3)
    np.testing.assert_allclose(rotations[1] @ rotations[1].T, np.eye(3), atol=1e-12)
    with pytest.raises(ValueError, match="q: expected 2 numbers"):
        model.body_frames([0.1])



def test_moment_arms_are_minus_the_path_lengths_slope(arm):
    model, _ = arm
    q = np.array([0.3, 1.2])
    r = model.moment_arms(q)
    assert r.shape == (len(model.muscles), len(model.joints))
    elbow = json.loads(model.to_json())  # the paper's arm: constant moment arms, in the file per joint
    for j, muscle in enumerate(elbow["muscles"]):
        arms = muscle["moment_arms_m"]
        expected = [arms.get(name, 0.0) for name in model.joints] if isinstance(arms, dict) else arms
        np.testing.assert_allclose(r[j], expected, atol=1e-12)


def test_each_muscle_line_passes_the_joints_it_crosses_on_the_side_it_pulls(arm):
    """In the arm's view (axes along +z, counter-clockwise positive), a positive moment arm turns
    the child counter-clockwise, so its muscle passes on the child's counter-clockwise side."""
    model, _ = arm
    skeleton = animation._Skeleton(model)
    for q in ([0.3, 1.2], [1.5, 0.2]):
        r = model.moment_arms(q)
        paths = skeleton.muscle_paths(np.array(q), r)
        segments = skeleton.segments(np.array(q))
        for j, path in enumerate(paths):
            crossed = [i for i in range(2) if abs(r[j, i]) > 0]
            assert path is not None and len(path) == len(crossed) + 2, model.muscles[j]
            for k, i in enumerate(crossed):
                start, end = segments[i]
                along = end - start
                offset = path[k + 1] - start
                assert np.linalg.norm(offset) > 0.005, "the line must not run through the joint"
                side = np.sign(along[0] * offset[1] - along[1] * offset[0])
                assert side == np.sign(r[j, i]), (model.muscles[j], i)
    # Biceps and triceps pass the elbow on opposite sides.
    sides = {m: np.sign(r[j, 1]) for j, m in enumerate(model.muscles) if r[j, 1] != 0}
    assert sides["biceps"] == -sides["triceps_short"]

def test_a_gif_of_a_plan_frame_by_frame(arm, tmp_path):
    model, scenario = arm
    plan = scenario.plan(model)
    times = np.linspace(0.0, scenario.duration, 61)
    s = plan.sample(times)
    frames = animation.animate(model, times, s["q"], s["activation"], tmp_path / "arm.gif", fps=10, speed=2.0)
    assert frames == 16  # 3 s at twice real time, 10 frames per second, and the first
    with Image.open(tmp_path / "arm.gif") as gif:
        assert gif.n_frames == frames
        first = np.asarray(gif.convert("RGB"))
        gif.seek(frames - 1)
        last = np.asarray(gif.convert("RGB"))
    assert np.abs(first.astype(int) - last).sum() > 0  # it moves
    assert oct(os.stat(tmp_path / "arm.gif").st_mode & 0o777) != oct(0o600)
    assert [p.name for p in tmp_path.iterdir()] == ["arm.gif"]  # no temporary left


def test_an_imported_model_is_drawn_in_its_sagittal_plane(knee, build_dir, models_dir, tmp_path):
    model, _ = knee
    skeleton = animation._Skeleton(model)
    e1, e2 = skeleton.plane
    np.testing.assert_allclose(np.cross(e1, e2), [0, 0, 1], atol=1e-12)  # seen from +z, y up
    (start, end), = skeleton.segments(np.radians([90.0]))
    (start0, end0), = skeleton.segments(np.radians([0.0]))
    np.testing.assert_allclose(start, start0, atol=1e-12)  # the knee stays where it is
    assert end0[1] < start0[1]  # straight: the shank hangs below the knee
    # Flexed 90 deg: the shank turned by a right angle about OpenSim's knee axis, 4.05 deg from
    # the view's normal, so the drawn angle is a right angle to within that tilt.
    a, b = end - start, end0 - start0
    drawn_deg = np.degrees(np.arccos(a @ b / np.linalg.norm(a) / np.linalg.norm(b)))
    assert abs(drawn_deg - 90.0) < 4.05, drawn_deg
    # The drawing is the projection of the bodies' 3-D positions on the ground plane z = const.
    origins, _ = model.body_frames(np.radians([90.0]))
    np.testing.assert_allclose(start, origins[0][:2], atol=1e-12)


def test_not_planar_and_bad_input_are_refused(arm, models_dir, tmp_path):
    model, scenario = arm
    data = json.loads((models_dir / "arm_richter_warner.json").read_text())
    data["joints"][1]["axis"] = [1.0, 0.0, 0.0]
    twisted = flatsos.Model.from_json(json.dumps(data), "twisted")
    t, q, a = np.linspace(0, 1, 5), np.zeros((5, 2)), np.full((5, 6), 0.1)
    with pytest.raises(ValueError, match="not planar: joint 'elbow' turns about"):
        animation.animate(twisted, t, q, a, tmp_path / "x.gif")
    for args, match in [((t, q[:4], a), "q: expected 5 rows of 2"), ((t, q, a[:, :5]), "activation: expected 5 rows"),
                        ((t[::-1], q, a), "time: expected at least two strictly increasing"),
                        ((t, q * np.nan, a), "finite")]:
        with pytest.raises(ValueError, match=match):
            animation.animate(model, *args, tmp_path / "x.gif")
    with pytest.raises(ValueError, match="must end in .gif or .mp4"):
        animation.animate(model, t, q, a, tmp_path / "x.png")
    from matplotlib.animation import FFMpegWriter
    if not FFMpegWriter.isAvailable():
        with pytest.raises(ValueError, match="needs ffmpeg"):
            animation.animate(model, t, q, a, tmp_path / "x.mp4")
    else:
        animation.animate(model, t, q, a, tmp_path / "x.mp4")
        assert (tmp_path / "x.mp4").stat().st_size > 0
    assert not list(tmp_path.iterdir())


def test_the_motion_file_names_opensims_coordinates_in_degrees(knee, tmp_path):
    model, scenario = knee
    plan = scenario.plan(model)
    times = np.linspace(0.0, scenario.duration, 11)
    q = plan.sample(times)["q"]
    sto.write_motion(model, times, q, tmp_path / "knee.mot")
    text = (tmp_path / "knee.mot").read_text()
    assert "inDegrees=yes" in text.split("endheader")[0]
    table = sto.read_sto(tmp_path / "knee.mot")
    held = model.held_coordinates
    assert {"hip_flexion_r", "hip_adduction_r", "hip_rotation_r"} <= set(held)
    assert list(table) == ["time", "knee_angle_r"] + sorted(held)
    for name, value in held.items():
        np.testing.assert_allclose(table[name], np.degrees(value), rtol=1e-15)
    np.testing.assert_allclose(table["knee_angle_r"], np.degrees(q[:, 0]), rtol=1e-15)
    np.testing.assert_allclose(table["hip_flexion_r"], 60.0, rtol=1e-12)  # held where the model was made
    np.testing.assert_allclose(table["hip_adduction_r"], 0.0)
    if not OSIM.exists():
        pytest.skip(f"{OSIM} is absent: the names are not checked against the original model")
    names = set(re.findall(r'<Coordinate name="([^"]+)"', OSIM.read_text()))
    assert set(table) - {"time"} <= names


def test_motion_file_errors(arm, tmp_path):
    model, _ = arm
    with pytest.raises(ValueError, match="time: must increase strictly"):
        sto.write_motion(model, [0.0, 0.0], np.zeros((2, 2)), tmp_path / "m.mot")
    with pytest.raises(ValueError, match="q: expected 2 rows of 2 angles"):
        sto.write_motion(model, [0.0, 1.0], np.zeros((2, 3)), tmp_path / "m.mot")
    (tmp_path / "bad.sto").write_text("x\nendheader\ntime\ta\n0\t1\t2\n")
    with pytest.raises(ValueError, match="bad.sto:4: 3 values for 2 columns"):
        sto.read_sto(tmp_path / "bad.sto")
    with pytest.raises(ValueError, match="not a storage file"):
        (tmp_path / "plain.txt").write_text("1 2 3\n")
        sto.read_sto(tmp_path / "plain.txt")
    assert not (tmp_path / "m.mot").exists()


def test_the_command_lines_on_a_programs_output(arm, build_dir, models_dir, tmp_path):
    model_file = str(models_dir / "seated_knee_r.json")
    program = subprocess.run([str(build_dir / "bin" / "arm_open_loop"), "--model", model_file, "--out",
                              str(tmp_path / "run")], capture_output=True, text=True)
    assert program.returncode == 0, program.stderr
    states = str(tmp_path / "run" / "simulation.sto")
    for module in ("flatsos.animation", "flatsos.sto"):
        shown = subprocess.run([sys.executable, "-m", module, "--help"], capture_output=True, text=True)
        assert shown.returncode == 0 and "--states" in shown.stdout
    made = subprocess.run([sys.executable, "-m", "flatsos.animation", "--model", model_file, "--states", states,
                           "--out", str(tmp_path / "knee.gif"), "--fps", "10"], capture_output=True, text=True)
    assert made.returncode == 0, made.stderr
    with Image.open(tmp_path / "knee.gif") as gif:
        assert gif.n_frames == 11
    moved = subprocess.run([sys.executable, "-m", "flatsos.sto", "--model", model_file, "--states", states,
                            "--out", str(tmp_path / "knee.mot")], capture_output=True, text=True)
    assert moved.returncode == 0, moved.stderr
    simulated = sto.read_sto(states)["/jointset/walker_knee_r/knee_angle_r/value"]
    np.testing.assert_allclose(sto.read_sto(tmp_path / "knee.mot")["knee_angle_r"], np.degrees(simulated), rtol=1e-15)
    wrong = subprocess.run([sys.executable, "-m", "flatsos.animation", "--model", str(models_dir / "arm_richter_warner.json"),
                            "--states", states, "--out", str(tmp_path / "arm.gif")], capture_output=True, text=True)
    assert wrong.returncode == 2
    assert "no column '/jointset/shoulder/shoulder/value'" in wrong.stderr
    assert not (tmp_path / "arm.gif").exists()
