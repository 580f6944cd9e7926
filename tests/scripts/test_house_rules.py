"""scripts/check_house_rules.py: it finds long functions, long files and includes that run back
up in synthetic trees, and the library itself keeps the rules."""
import importlib.util
import pathlib
import textwrap

REPO = pathlib.Path(__file__).resolve().parents[2]
spec = importlib.util.spec_from_file_location("check_house_rules", REPO / "scripts" / "check_house_rules.py")
rules = importlib.util.module_from_spec(spec)
spec.loader.exec_module(rules)


def write(root, relative, text):
    path = root / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text))


def function_of(name, body_lines):
    body = "".join(f"  x += {i};  // {{ not a brace }}\n" for i in range(body_lines))
    return f"int {name}(int x) {{\n  auto f = [&](int y) {{ return y; }};\n{body}  return f(x);\n}}\n"


def test_functions_are_measured_from_signature_to_closing_brace():
    text = "namespace a {\nstruct S {\n  int m() const { return 1; }\n};\n" + function_of("long_one", 99) + "}\n"
    found = {name: (first, last) for name, first, last in rules.functions(text)}
    assert found["long_one"] == (5, 5 + 99 + 3)  # signature, lambda, 99 lines, return, brace
    assert found["m"] == (3, 3)


def test_violations_are_found(tmp_path):
    write(tmp_path, "planner/src/sos/fine.cpp", function_of("short_one", 10))
    write(tmp_path, "planner/src/sos/long.cpp", function_of("too_long", 100))
    write(tmp_path, "plugin/src/big.cpp", "// line\n" * 451)
    write(tmp_path, "planner/src/sos/up.cpp", '#include "path/free_path.hpp"\n#include "flatsos/planner/motion_planner.hpp"\n')
    write(tmp_path, "planner/include/flatsos/planner/product.hpp", '#include "flatsos/planner/x_study.hpp"\n')
    write(tmp_path, "muscles/src/empty.cpp", "")
    problems = "\n".join(rules.check(tmp_path))
    assert "too_long has 104 lines" in problems
    assert "short_one" not in problems
    assert "plugin/src/big.cpp: 451 lines" in problems
    assert "includes path/free_path.hpp of the later room path" in problems
    assert "includes the facade" in problems
    assert "includes the study header" in problems
    assert len(rules.check(tmp_path)) == 5


def test_the_library_keeps_the_house_rules():
    assert rules.check(REPO) == []
