"""The README's Python quickstart and its five-minute tour, executed as written from a repository
root whose build/ is the build under test."""
import contextlib
import io
import json
import os
import pathlib
import re
import subprocess

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BUILD_DIR = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR", SOURCE_DIR / "build"))


def readme_block(section, language):
    readme = (SOURCE_DIR / "README.md").read_text()
    text = readme.split(f"\n## {section}\n", 1)[1].split("\n## ", 1)[0]
    block = re.search(rf"```{language}\n(.*?)```", text, re.S)
    assert block, f"no {language} block in the README's section '{section}'"
    return block.group(1)


@pytest.fixture
def repository_root(tmp_path):
    """A root like the README's: models/ and scripts/ from the source, build/ the build under test."""
    for name in ("models", "scripts"):
        (tmp_path / name).symlink_to(SOURCE_DIR / name)
    (tmp_path / "build").symlink_to(BUILD_DIR)
    return tmp_path


def test_the_readme_quickstart_runs_as_written(monkeypatch, repository_root):
    monkeypatch.chdir(repository_root)
    out = io.StringIO()
    namespace = {}
    with contextlib.redirect_stdout(out):
        exec(compile(readme_block("Python", "python"), "README.md", "exec"), namespace)
    plan, run = namespace["plan"], namespace["run"]
    assert plan.status == "solved", plan.message
    assert plan.effort == "excitation_squared"
    assert "solved excitation_squared" in out.getvalue()
    assert namespace["s"]["excitation"].max() <= 1.0 + 1e-6
    assert abs(run["q"][-1] - namespace["s"]["q"][-1]).max() < 1e-4 * 3.14159 / 180


def test_the_readme_tour_runs_as_written(repository_root):
    tour = readme_block("A five-minute tour", "sh")
    done = subprocess.run(["bash", "-euo", "pipefail", "-c", tour], cwd=repository_root, capture_output=True, text=True)
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    results = repository_root / "results" / "tour"
    plan = json.loads((results / "plan" / "summary.json").read_text())
    control = json.loads((results / "control" / "summary.json").read_text())
    assert plan["status"] == "solved", plan.get("message")
    assert control["success"] is True, control.get("message")
    for made in ("plan/plan.sto", "plan/simulation_controls.sto", "plan/open_loop_activations.png",
                 "control/simulation.sto", "control/rh_joint_angles.png", "control/motion.gif"):
        assert (results / made).stat().st_size > 0, made
