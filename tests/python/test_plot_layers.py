"""scripts/plot_results.py draws what could vanish on top: a planned excitation that equals the
activation stays visible over it, a muscle at its reserve over the reserve line."""
import importlib.util
import os
import pathlib
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BUILD_DIR = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR", SOURCE_DIR / "build"))


def plot_module():
    spec = importlib.util.spec_from_file_location("plot_results", SOURCE_DIR / "scripts" / "plot_results.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def open_loop_figures(tmp_path_factory):
    out = tmp_path_factory.mktemp("plot") / "open_loop"
    subprocess.run([str(BUILD_DIR / "bin" / "arm_open_loop"), "--model", str(SOURCE_DIR / "models" / "elbow_1dof.json"),
                    "--out", str(out)], check=True, capture_output=True)
    plot = plot_module()
    figures = {}
    plot.save = lambda fig, folder, name, scales, report: figures.setdefault(name, fig)
    plot.open_loop(str(out), False)
    return figures


def line_labelled(ax, label):
    lines = [line for line in ax.get_lines() if line.get_label() == label]
    assert len(lines) == 1, [line.get_label() for line in ax.get_lines()]
    return lines[0]


def test_the_planned_excitation_is_drawn_over_the_activation(open_loop_figures):
    panels = [ax for ax in open_loop_figures["open_loop_activations.png"].axes if ax.get_lines()]
    assert len(panels) == 3
    for ax in panels:
        over = line_labelled(ax, "planned excitation").get_zorder()
        assert over > line_labelled(ax, "planned activation").get_zorder()
        assert over > line_labelled(ax, "simulated activation").get_zorder()


def test_every_tendon_force_is_drawn_over_the_reserve_line(open_loop_figures):
    forces = open_loop_figures["open_loop_joints_forces.png"].axes[1]
    reserve = line_labelled(forces, "reserve 10 N")
    muscles = [line for line in forces.get_lines() if line is not reserve]
    assert len(muscles) == 3
    # The plan holds some muscle at its reserve: that is the line that could vanish.
    assert min(line.get_ydata().min() for line in muscles) == pytest.approx(10.0, abs=0.01)
    assert all(line.get_zorder() > reserve.get_zorder() for line in muscles)
