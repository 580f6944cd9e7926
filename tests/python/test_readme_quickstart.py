"""The README's Python quickstart, executed as written from the repository's root."""
import contextlib
import io
import os
import pathlib
import re

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]


def test_the_readme_quickstart_runs_as_written(monkeypatch):
    readme = (SOURCE_DIR / "README.md").read_text()
    section = readme.split("\n## Python\n", 1)[1]
    block = re.search(r"```python\n(.*?)```", section, re.S)
    assert block, "no Python block in the README's Python section"
    monkeypatch.chdir(SOURCE_DIR)
    out = io.StringIO()
    namespace = {}
    with contextlib.redirect_stdout(out):
        exec(compile(block.group(1), "README.md", "exec"), namespace)
    plan = namespace["plan"]
    assert plan.status == "solved", plan.message
    assert "solved" in out.getvalue()
    assert namespace["s"]["excitation"].max() <= 1.0 + 1e-6
    assert os.path.isfile(SOURCE_DIR / "models" / "arm_richter_warner.json")
