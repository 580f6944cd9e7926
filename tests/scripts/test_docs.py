"""The front door's promises: a short README whose code blocks are all run by a named test, links
that resolve (files and headings), and a model format page that matches the loader."""
import os
import pathlib
import re
import subprocess
import tempfile

import pytest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
README = SOURCE_DIR / "README.md"
README_MAX_LINES = 260

FENCE = re.compile(r"^```(\w*)\n(.*?)^```\n", re.S | re.M)
RUN_BY = re.compile(r"<!-- run by: (.*?) -->\n$")
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def readme_blocks():
    """(language, code, the 'run by' comment right above the block or None), in order."""
    text = README.read_text()
    blocks = []
    for m in FENCE.finditer(text):
        before = text[: m.start()]
        run_by = RUN_BY.search(before)
        blocks.append((m.group(1), m.group(2), run_by.group(1) if run_by else None))
    return blocks


def documentation_files():
    return [README, SOURCE_DIR / "CONTRIBUTING.md", *sorted((SOURCE_DIR / "docs").rglob("*.md"))]


def heading_slugs(path):
    """GitHub's anchors: lower case, punctuation dropped, spaces to hyphens (outside code blocks)."""
    text = FENCE.sub("", path.read_text())
    slugs = set()
    for line in text.split("\n"):
        m = re.match(r"#+ (.*)", line)
        if m:
            title = re.sub(r"[`*]", "", m.group(1).strip().lower())
            slugs.add(re.sub(r"[^\w\- ]", "", title).replace(" ", "-"))
    return slugs


def test_the_readme_is_a_guide_not_a_record():
    lines = README.read_text().count("\n")
    assert lines <= README_MAX_LINES, f"README.md has {lines} lines (at most {README_MAX_LINES})"


def test_every_readme_block_names_the_test_that_runs_it():
    blocks = readme_blocks()
    first_language, first_code, _ = blocks[0]
    # The first block is the two commands of a fresh machine: CI (.ci/run) runs scripts/test.sh,
    # and scripts/demo.sh runs the tour's programs on the shipped scenarios.
    assert first_language == "sh" and re.findall(r"^(\S+)", first_code, re.M) == ["scripts/demo.sh", "scripts/test.sh"]
    for name in ("scripts/demo.sh", "scripts/test.sh"):
        assert os.access(SOURCE_DIR / name, os.X_OK), name
    for language, code, run_by in blocks[1:]:
        assert run_by, f"README block without a <!-- run by: ... --> comment:\n{code[:200]}"
        for named in re.findall(r"(?:tests|scripts|examples)/[\w/.]+\w", run_by):
            assert (SOURCE_DIR / named).exists(), f"README block says it is run by {named}, which does not exist"


def test_the_readme_cpp_block_is_the_example_the_tests_build():
    cpp = [code for language, code, _ in readme_blocks() if language == "cpp"]
    assert len(cpp) == 1
    assert cpp[0] == (SOURCE_DIR / "examples" / "readme" / "plan_elbow.cpp").read_text()
    assert "readme_cpp_example" in (SOURCE_DIR / "tests" / "CMakeLists.txt").read_text()


def test_the_readme_build_for_use_configures_without_tests():
    install = [code for language, code, _ in readme_blocks() if "FLATSOS_BUILD_TESTS=OFF" in code]
    assert len(install) == 1
    configure = re.search(r"^cmake -S \. -B build (-D\S+)", install[0], re.M)
    assert configure, install[0]
    with tempfile.TemporaryDirectory() as build:
        done = subprocess.run(["cmake", "-S", str(SOURCE_DIR), "-B", build, configure.group(1)],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr[-2000:]
        # No test target is generated: the build for use compiles no test.
        makefile = (pathlib.Path(build) / "Makefile").read_text()
        assert "test_planner" not in makefile and "test_plugin" not in makefile
        assert re.search(r"^flatsos *:", makefile, re.M)  # the programs (their old names link to it)


@pytest.mark.parametrize("doc", documentation_files(), ids=lambda p: str(p.relative_to(SOURCE_DIR)))
def test_every_relative_link_resolves(doc):
    text = FENCE.sub("", doc.read_text())
    broken = []
    for target in LINK.findall(text):
        if re.match(r"[a-z]+:", target):
            continue  # an address outside the repository
        path, _, anchor = target.partition("#")
        file = (doc.parent / path).resolve() if path else doc
        if not file.exists():
            broken.append(f"{target}: no such file")
        elif anchor and file.suffix == ".md" and anchor not in heading_slugs(file):
            broken.append(f"{target}: no heading '{anchor}' in {file.name}")
    assert not broken, "\n".join(broken)


def keys_the_loader_reads():
    """Every key the model file's reader asks for, from its sources and the tables it reads by."""
    read = set()
    for reader in ("plugin/src/io/model_file.cpp", "plugin/src/io/model_file_millard.cpp"):
        # Keys the reader asks for (r.number("..."), has("..."), ...), not its messages' words.
        calls = r'(?<!\)\.)\b(?:has|find|at|get|indexed|number|numbers|positive|string|vec3)\("([a-z][A-Za-z0-9_]*)"'
        source = (SOURCE_DIR / reader).read_text()
        read |= set(re.findall(calls, source))
        read |= set(re.findall(r'\w+_key = "([a-z][A-Za-z0-9_]*)"', source))  # inertia_key = "...", arms_key
    fields = (SOURCE_DIR / "plugin/src/io/model_file_fields.hpp").read_text()
    read |= set(re.findall(r'\{"([a-z][A-Za-z0-9_]*)",\s*&muscles::MuscleParameters', fields))
    read |= set(re.findall(r'constexpr const char\* k\w+Key = "([a-z0-9_]+)"', fields))
    millard = (SOURCE_DIR / "plugin/src/io/model_file_millard.hpp").read_text()
    read |= set(re.findall(r'constexpr const char\* k\w+Key = "([a-z0-9_]+)"', millard))
    description = (SOURCE_DIR / "plugin/src/model/model_description.cpp").read_text()
    for names in re.findall(r"JointFieldNames \w+\{(.*?)\}", description):
        read |= set(re.findall(r'"([a-z][A-Za-z0-9_]*)"', names))
    curves = (SOURCE_DIR / "plugin/src/io/millard2012_fields.hpp").read_text()
    read |= set(re.findall(r'visit\(curve, key, "([a-z_]+)"', curves))
    read |= set(re.findall(r'key = "([a-z_]+)"', curves))
    assert len(read) > 60, sorted(read)
    return read


def test_the_model_format_page_documents_every_key_the_loader_reads():
    page = (SOURCE_DIR / "docs" / "model_format.md").read_text()
    documented = set(re.findall(r"`([a-z][A-Za-z0-9_]*)`", page))
    missing = sorted(keys_the_loader_reads() - documented)
    assert not missing, f"keys the loader reads but docs/model_format.md does not name: {missing}"


def schema_keys(node):
    """Every property name a JSON Schema declares, at any depth."""
    keys = set()
    if isinstance(node, dict):
        keys |= set(node.get("properties", {}))
        for value in node.values():
            keys |= schema_keys(value)
    elif isinstance(node, list):
        for value in node:
            keys |= schema_keys(value)
    return keys


def test_the_model_schema_declares_the_keys_the_loader_reads_and_no_other():
    import json
    schema = json.loads((SOURCE_DIR / "docs" / "model.schema.json").read_text())
    declared = schema_keys(schema)
    # The Millard curves' properties are OpenSim's names, free-form in the schema (numbers).
    curves = set(re.findall(r'visit\(curve, key, "([a-z_]+)"',
                            (SOURCE_DIR / "plugin/src/io/millard2012_fields.hpp").read_text()))
    read = keys_the_loader_reads() - curves
    assert not sorted(read - declared), f"keys the loader reads but the schema does not declare: {sorted(read - declared)}"
    assert not sorted(declared - read), f"keys the schema declares but the loader does not read: {sorted(declared - read)}"


def test_the_model_format_page_names_no_key_the_loader_does_not_know():
    page = (SOURCE_DIR / "docs" / "model_format.md").read_text()
    table_keys = set(re.findall(r"^\| `([a-z][A-Za-z0-9_]*)`", page, re.M))
    assert len(table_keys) > 40
    unknown = sorted(table_keys - keys_the_loader_reads())
    assert not unknown, f"docs/model_format.md names keys the loader does not read: {unknown}"
