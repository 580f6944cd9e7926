#!/usr/bin/env python3
"""The library's house rules, checked on its sources (muscles/, plugin/, planner/):

- no source file above 450 lines;
- no function above 100 lines (from its signature's first line to its closing brace; lambdas
  count as part of the function that holds them);
- no stage includes the facade or a later stage: the planner's private headers are included by
  their room ("sos/...", "path/..."), and a room only includes rooms listed before it in ROOMS;
- no product header includes a study header (*_study.hpp).

Prints every violation and exits 1 if there is any. Usage: check_house_rules.py [REPO]
"""
import argparse
import pathlib
import re
import sys

MAX_FILE_LINES = 450
MAX_FUNCTION_LINES = 100
LIBRARY_FOLDERS = ("muscles", "plugin", "planner")
# The planner's rooms in pipeline order: a room may include its own headers and those of rooms
# before it, never those after it.
ROOMS = ("numerics", "flatness", "bounds", "sos", "open_loop", "path", "collocation", "receding_horizon", "facade")
# Facade headers no stage may include.
FACADES = ("flatsos/planner/motion_planner.hpp",)

KEYWORDS_BEFORE_BRACE = re.compile(
    r"\b(namespace|class|struct|union|enum|if|for|while|switch|do|else|try|catch|return|case)\b")


def strip_comments_and_strings(text):
    """The text with comments, string and character literals blanked (newlines kept)."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i):
            m = re.match(r'R"([^(]*)\(', text[i:])
            end = text.find(")" + m.group(1) + '"', i) if m else -1
            j = n if end < 0 else end + len(m.group(1)) + 2
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:j]))
            i = j
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + " " * (j - i - 1) + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def functions(text):
    """(name, first line, last line) of each function body outside other function bodies."""
    code = strip_comments_and_strings(text)
    found = []
    stack = []  # per open brace: is it a function body?
    statement_start = 0
    for i, c in enumerate(code):
        if c == "{":
            head = code[statement_start:i]
            inside_function = any(stack)
            is_function = False
            if not inside_function:
                flat = " ".join(head.split())
                if ")" in flat and not KEYWORDS_BEFORE_BRACE.match(flat.lstrip()) and "=" not in flat.split("(")[0]:
                    name = re.findall(r"([~\w:]+)\s*\(", flat)
                    if name and name[0] not in ("if", "for", "while", "switch", "catch"):
                        is_function = True
                        first = code.count("\n", 0, statement_start + len(head) - len(head.lstrip())) + 1
                        found.append([name[0], first, None, len(stack)])
            stack.append(is_function)
            statement_start = i + 1
        elif c == "}":
            if stack and stack.pop() and not any(stack):
                for f in reversed(found):
                    if f[2] is None:
                        f[2] = code.count("\n", 0, i) + 1
                        break
            statement_start = i + 1
        elif c == ";" or (c == ":" and not any(stack) and code[i - 1] != ":" and code[i + 1: i + 2] != ":"
                          and re.search(r"\b(public|private|protected)\s*$", code[statement_start:i])):
            statement_start = i + 1
    return [(name, first, last) for name, first, last, _ in found if last is not None]


def library_sources(repo):
    for folder in LIBRARY_FOLDERS:
        for path in sorted((repo / folder).rglob("*")):
            if path.suffix in (".cpp", ".hpp") and path.is_file():
                yield path


def room_of(path, repo):
    parts = path.relative_to(repo).parts
    if len(parts) > 3 and parts[0] == "planner" and parts[1] == "src":
        return parts[2]
    return None


def check(repo):
    problems = []
    for path in library_sources(repo):
        rel = path.relative_to(repo)
        text = path.read_text(encoding="utf-8")
        lines = text.count("\n") + (0 if text.endswith("\n") else 1)
        if lines > MAX_FILE_LINES:
            problems.append(f"{rel}: {lines} lines (at most {MAX_FILE_LINES})")
        for name, first, last in functions(text):
            length = last - first + 1
            if length > MAX_FUNCTION_LINES:
                problems.append(f"{rel}:{first}: function {name} has {length} lines (at most {MAX_FUNCTION_LINES})")
        includes = re.findall(r'^#include "([^"]+)"', text, flags=re.M)
        room = room_of(path, repo)
        if room is not None:
            for inc in includes:
                if inc in FACADES:
                    problems.append(f"{rel}: includes the facade {inc}")
                target = inc.split("/")[0]
                if target in ROOMS and room in ROOMS and ROOMS.index(target) > ROOMS.index(room):
                    problems.append(f"{rel}: room {room} includes {inc} of the later room {target}")
        if not rel.name.endswith("_study.hpp") and rel.parts[1] == "include":
            for inc in includes:
                if inc.endswith("_study.hpp"):
                    problems.append(f"{rel}: a product header includes the study header {inc}")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("repo", nargs="?", default=pathlib.Path(__file__).resolve().parent.parent, type=pathlib.Path,
                        help="the repository's root (default: this script's)")
    args = parser.parse_args()
    problems = check(args.repo.resolve())
    for p in problems:
        print(p)
    print(f"house rules: {len(problems)} violation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
