"""`pip install .` and `python3 -m build` from a copy of the source tree, offline: the package
installs into a fresh virtual environment (Debian's numpy through --system-site-packages) and
plans the paper's scenario there. The C++ module comes from the build under test
(FLATSOS_BUILD_DIR, which setup.py reuses) instead of a second build of the library."""
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
BUILD_DIR = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR", SOURCE_DIR / "build"))
PLANS_THE_PAPERS_SCENARIO = """
import numpy as np, flatsos, sys
assert flatsos.__file__.startswith(sys.prefix), flatsos.__file__
arm = flatsos.Model(sys.argv[1])
# The paper's scenario (section 5): its start, activations and target, its quartic.
plan = flatsos.plan_open_loop(arm, q0=np.radians([0, 10]), qd0=np.radians([0.0573, 0.1146]),
                              a0=[0.135, 0.040, 0.404, 0.556, 0.414, 0.068], target=np.radians([90, 0]),
                              duration=3.0, reserves=10.0, preset="paper")
print(plan.status, round(plan.cost, 2))
"""


@pytest.fixture(scope="module")
def source_copy(tmp_path_factory):
    """The source tree without build folders, as a clone has it."""
    copy = tmp_path_factory.mktemp("flatsos") / "src"
    shutil.copytree(SOURCE_DIR, copy, ignore=shutil.ignore_patterns("build", "build-*", ".git", "results", "__pycache__"))
    return copy


def clean_environment():
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}  # the build tree's module must not leak in
    env["FLATSOS_BUILD_DIR"] = str(BUILD_DIR)
    env["PIP_NO_INDEX"] = "1"  # offline: nothing is downloaded
    return env


def test_pip_install_into_a_fresh_virtual_environment_plans_the_papers_scenario(source_copy, tmp_path):
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    python = venv / "bin" / "python"
    done = subprocess.run([str(python), "-m", "pip", "install", "--no-build-isolation", str(source_copy)],
                          capture_output=True, text=True, env=clean_environment())
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    model = source_copy / "models" / "arm_richter_warner.json"
    run = subprocess.run([str(python), "-c", PLANS_THE_PAPERS_SCENARIO, str(model)], capture_output=True, text=True,
                         env=clean_environment(), cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-3000:]
    assert run.stdout.split() == ["solved", "958.32"]


def test_python_build_makes_a_wheel_with_the_module(source_copy, tmp_path):
    pytest.importorskip("build", reason="python3-build (scripts/install_deps.sh installs it)")
    done = subprocess.run([sys.executable, "-m", "build", "--no-isolation", "--wheel", "--outdir", str(tmp_path),
                           str(source_copy)], capture_output=True, text=True, env=clean_environment())
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    wheels = list(tmp_path.glob("flatsos-0.1.0-*.whl"))
    assert len(wheels) == 1, list(tmp_path.iterdir())
    import zipfile
    names = zipfile.ZipFile(wheels[0]).namelist()
    assert any(n.startswith("flatsos/_flatsos") and n.endswith(".so") for n in names), names
    assert {"flatsos/__init__.py", "flatsos/study.py", "flatsos/sto.py"} <= set(names)
    assert not any(n.endswith(".a") for n in names), names
