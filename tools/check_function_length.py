#!/usr/bin/env python3
"""Lists every C and C++ function longer than 120 lines and exits 1 if there is one.

A function's length is its lines from its name to its closing brace, as universal-ctags
reports them (`ctags --fields=+ne`); a lambda counts inside its function and on its own. Reads
every .c/.cc/.cpp/.h/.hpp file under the source tree (libraries, exe, tools, tests, bench, fuzz,
python/src), except build directories, node_modules and hidden directories. Each run first
checks itself on a generated file (a 121-line function fails, a 120-line one passes), so a
ctags that no longer reports end lines fails the check instead of passing it.

Usage: tools/check_function_length.py [SOURCE_DIR]
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

MAX_LINES = 120

# Debian's universal-ctags installs this name; `ctags` may be another ctags's alternative.
CTAGS = shutil.which("ctags-universal") or "ctags"
SUFFIXES = {".c", ".cc", ".cpp", ".h", ".hpp"}


def skipped_dir(name):
    return name.startswith("build") or name.startswith(".") or name == "node_modules"


def source_files(root):
    for folder, dirs, files in os.walk(root):
        dirs[:] = sorted(d for d in dirs if not skipped_dir(d))
        for f in sorted(files):
            if Path(f).suffix in SUFFIXES:
                yield Path(folder, f).relative_to(root)


def display_name(tag):
    """The function's name as a reader looks for it: Class::Method, TEST_F(Suite, Name)."""
    name = tag["name"]
    if name in ("TEST", "TEST_F", "TEST_P"):
        return name + tag.get("signature", "()").replace(",", ", ")
    if tag.get("scopeKind") in ("class", "struct"):
        return tag["scope"].split("::")[-1] + "::" + name
    if name.startswith("__anon"):
        return "lambda in " + tag.get("scope", "?").split("::")[-1]
    return name


def long_functions(root, files):
    """(path, line, name, length) of every function over MAX_LINES lines in files."""
    if not files:
        return []
    # The C files too as C++: the C API's consumer test is one.
    command = [CTAGS, "--output-format=json", "--fields=+neS", "--language-force=C++",
               "--kinds-c++=f", "-f", "-", "-L", "-"]
    run = subprocess.run(command, cwd=root, input="\n".join(str(f) for f in files),
                         capture_output=True, text=True, check=True)
    found = []
    for line in run.stdout.splitlines():
        tag = json.loads(line)
        if tag.get("_type") != "tag":
            continue
        if "end" not in tag:
            sys.exit(f"check_function_length: ctags gave no end line for {tag['path']}:"
                     f"{tag['line']} {tag['name']}")
        length = tag["end"] - tag["line"] + 1
        if length > MAX_LINES:
            found.append((tag["path"], tag["line"], display_name(tag), length))
    return sorted(found)


def self_check():
    """The check fails a MAX_LINES + 1 line function (also a lambda's and in a namespace) and
    passes a MAX_LINES one."""
    def function(name, lines):  # `lines` lines from its name to its closing brace
        return [f"int {name}() {{"] + ["  ++x;"] * (lines - 3) + ["  return x;", "}"]

    def lambda_in(name, lines):
        body = ["  auto f = [&] {"] + ["    ++x;"] * (lines - 2) + ["  };"]
        return [f"int {name}() {{"] + body + ["  return f();", "}"]

    source = (["namespace cwloc {", "int x = 0;"] + function("Short", MAX_LINES) +
              function("Long", MAX_LINES + 1) + ["TEST_F(Suite, LongTest) {"] +
              ["  ++x;"] * (MAX_LINES - 1) + ["}"] + lambda_in("WithLambda", MAX_LINES + 1) +
              ["}  // namespace cwloc"])
    with tempfile.TemporaryDirectory() as tmp:
        Path(tmp, "sample.cc").write_text("\n".join(source) + "\n")
        got = {(name, length) for _, _, name, length in long_functions(tmp, ["sample.cc"])}
    want = {("Long", MAX_LINES + 1), ("TEST_F(Suite, LongTest)", MAX_LINES + 1),
            ("WithLambda", MAX_LINES + 4), ("lambda in WithLambda", MAX_LINES + 1)}
    if got != want:
        sys.exit(f"check_function_length: self-check failed: expected {sorted(want)}, "
                 f"ctags gave {sorted(got)}")


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent)
    self_check()
    files = list(source_files(root))
    failing = long_functions(root, files)
    for path, line, name, length in failing:
        print(f"{path}:{line}: {name} is {length} lines, over {MAX_LINES}")
    if failing:
        print(f"check_function_length: {len(failing)} functions over {MAX_LINES} lines: split "
              "each into named stages", file=sys.stderr)
        return 1
    print(f"check_function_length: no function over {MAX_LINES} lines in {len(files)} files")
    return 0


if __name__ == "__main__":
    sys.exit(main())
