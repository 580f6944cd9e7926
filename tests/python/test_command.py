"""`flatsos <subcommand>`: one command for every program, the old program names unchanged."""
import json
import os
import pathlib
import subprocess

import pytest

BUILD_DIR = pathlib.Path(os.environ.get("FLATSOS_BUILD_DIR", pathlib.Path(__file__).resolve().parents[2] / "build"))
FLATSOS = BUILD_DIR / "bin" / "flatsos"
MODEL = BUILD_DIR / "share" / "flatsos" / "models" / "elbow_1dof.json"
SUBCOMMANDS = {"plan": "arm_open_loop", "control": "arm_receding_horizon", "track": "track_motion",
               "static-optimization": "static_optimization", "simulate": "arm_forward",
               "import": "opensim_to_model", "process-motion": "process_motion", "bench": "flatsos_bench",
               "study": "flatsos.study", "animate": "flatsos.animation", "motion": "flatsos.sto",
               "plot": "plot_results.py"}


def flatsos(*args, cwd=None):
    return subprocess.run([str(FLATSOS), *args], capture_output=True, text=True, cwd=cwd, timeout=600)


def test_help_lists_every_subcommand():
    done = flatsos("--help")
    assert done.returncode == 0
    listed = [line.split()[0] for line in done.stdout.split("Subcommands:\n")[1].split("\n\n")[0].splitlines()]
    assert listed == list(SUBCOMMANDS)


@pytest.mark.parametrize("args", [[], ["frobnicate"]], ids=["none", "unknown"])
def test_a_missing_or_unknown_subcommand_is_a_usage_error(args):
    done = flatsos(*args)
    assert done.returncode == 2
    assert "Usage: flatsos <subcommand>" in done.stderr
    if args:
        assert "unknown subcommand 'frobnicate'" in done.stderr


@pytest.mark.parametrize("name", list(SUBCOMMANDS))
def test_each_subcommand_has_the_help_of_its_program(name):
    done = flatsos(name, "--help")
    assert done.returncode == 0, done.stderr
    program = SUBCOMMANDS[name]
    if program.startswith("flatsos."):
        assert f"python3 -m {program}" in done.stdout or "usage:" in done.stdout
    elif program.endswith(".py"):
        assert f"Usage: {program}" in done.stdout
    else:
        assert f"Usage: flatsos {name} [OPTIONS]" in done.stdout
        alias = subprocess.run([str(BUILD_DIR / "bin" / program), "--help"], capture_output=True, text=True)
        assert alias.returncode == 0 and alias.stdout.replace(str(BUILD_DIR / "bin" / program), f"flatsos {name}") \
            .replace(f"Usage: {BUILD_DIR / 'bin' / program}", f"Usage: flatsos {name}") == done.stdout


def test_plan_plans_and_a_bad_option_exits_2(tmp_path):
    done = flatsos("plan", "--model", str(MODEL), "--effort", "excitation_squared", "--out", "plan", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "plan" / "summary.json").read_text())
    assert summary["status"] == "solved" and summary["effort"] == "excitation_squared"
    assert flatsos("plan", "--no-such-option", cwd=tmp_path).returncode == 2
    drawn = flatsos("plot", "plan", cwd=tmp_path)
    assert drawn.returncode == 0, drawn.stderr
    assert (tmp_path / "plan" / "open_loop_activations.png").stat().st_size > 0


def test_a_program_not_built_is_named_with_how_to_build_it(tmp_path):
    # A build for use has no benchmarks: the command alone in a folder stands for it.
    (tmp_path / "bin").mkdir()
    alone = tmp_path / "bin" / "flatsos"
    alone.write_bytes(FLATSOS.read_bytes())
    alone.chmod(0o755)
    done = subprocess.run([str(alone), "bench", "--help"], capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert "flatsos bench: flatsos_bench is not built beside this program" in done.stderr
    assert "-DFLATSOS_BUILD_BENCH=ON" in done.stderr
