#!/usr/bin/env python3
"""Lists the tests a ctest run skipped, and fails CI for a skip tests/allowed_skips.txt does not
allow: a test that skips for a missing dependency or missing ../shared data tests nothing.

    tools/check_skips.py [--build release|asan] [--allowed FILE] BUILD_DIR_OR_CTEST_LOG

Reads ctest's full log (BUILD_DIR/Testing/Temporary/LastTest.log): a GoogleTest test skipped
(GTEST_SKIP, "[  SKIPPED ]" in its output; CTest reports it skipped through
SKIP_REGULAR_EXPRESSION) and each pytest test python_tests skipped ("SKIPPED" in pytest -vv's
lines, and whole modules in its -rs summary). Prints every skip with its reason. Exit 1 when one
is not allowed for BUILD and CI is set (.ci/run sets CI=true) or --strict is given; otherwise
the skips are printed loudly and the exit is 0. Tests left out by ctest -E never ran, so they
are not skips.
"""
import argparse
import fnmatch
import os
import re
import sys
from pathlib import Path

SOURCE = Path(__file__).resolve().parent.parent
BUILDS = ("release", "asan", "any")


def read_allowed(path):
    """[(build, pattern, reason)] of the allowed-skips file (BUILD TEST REASON per line)."""
    allowed = []
    for number, line in enumerate(path.read_text().splitlines(), 1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = line.split(None, 2)
        if len(fields) < 3 or fields[0] not in BUILDS:
            sys.exit(f"{path}:{number}: expected BUILD TEST REASON (BUILD: {', '.join(BUILDS)})")
        allowed.append(tuple(fields))
    return allowed


def test_blocks(log):
    """(ctest name, output) of every test in a LastTest.log."""
    name, output, inside = None, [], False
    for line in log.splitlines():
        start = re.match(r"^\d+/\d+ Testing: (.*)$", line)
        if start:
            # A parameterised test's ctest name goes on with "  # GetParam() = ...".
            name, output, inside = start.group(1).split("  #")[0].strip(), [], False
        elif name is not None and line == "Output:":
            inside = True
        elif inside and line == "<end of output>":
            yield name, output
            name, inside = None, False
        elif inside:
            output.append(line)


def gtest_skip(output):
    """The reason a GoogleTest test skipped, or None when it did not."""
    if not any(line.startswith("[  SKIPPED ]") for line in output):
        return None
    reason, collecting = [], False
    for line in output:
        if re.search(r":\d+: Skipped$", line):
            collecting = True
        elif line.startswith("[  SKIPPED ]"):
            break
        elif collecting and line.strip():
            reason.append(line.strip())
    return " ".join(reason) or "(no message)"


def pytest_skips(output):
    """[(node id, reason)] of the tests pytest -vv -rs skipped, whole modules included."""
    skips = []
    for line in output:
        test = re.match(r"^(\S+::\S+) SKIPPED(?: \((.*)\))?(?:\s+\[\s*\d+%\])?\s*$", line)
        if test:
            skips.append((test.group(1), test.group(2) or "(no message)"))
    tested_files = {node.split("::")[0] for node, _ in skips}
    for line in output:
        # A module skipped at import (pytest.importorskip) has no test line, only its summary.
        summary = re.match(r"^SKIPPED \[\d+\] ([^:]+):\d+: (.*)$", line)
        module = summary.group(1) if summary else ""
        if module.endswith(".py") and Path(module).name != "conftest.py":
            if module not in tested_files and not any(r == summary.group(2) for _, r in skips):
                skips.append((module, summary.group(2)))
    return skips


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("log", type=Path, help="a build folder or a ctest LastTest.log")
    parser.add_argument("--build", default="release", choices=BUILDS[:2])
    parser.add_argument("--allowed", type=Path, default=SOURCE / "tests" / "allowed_skips.txt")
    parser.add_argument("--strict", action="store_true", help="fail as in CI")
    args = parser.parse_args()
    log = args.log / "Testing" / "Temporary" / "LastTest.log" if args.log.is_dir() else args.log
    if not log.is_file():
        sys.exit(f"check_skips: no ctest log at {log}")
    allowed = read_allowed(args.allowed)
    strict = args.strict or os.environ.get("CI", "").lower() in ("1", "true", "yes")

    skips, ran = [], 0
    for name, output in test_blocks(log.read_text(errors="replace")):
        ran += 1
        if name == "python_tests":
            skips += pytest_skips(output)
        else:
            reason = gtest_skip(output)
            if reason is not None:
                skips.append((name, reason))

    def allowance(test):
        for build, pattern, reason in allowed:
            if build in (args.build, "any") and fnmatch.fnmatchcase(test, pattern):
                return reason
        return None

    unallowed = [(test, reason) for test, reason in skips if allowance(test) is None]
    print(f"check_skips: {len(skips)} tests skipped ({ran} ctest tests in {log}; "
          f"{len(skips) - len(unallowed)} skips allowed for '{args.build}' by {args.allowed.name})")
    for test, reason in skips:
        note = "allowed" if allowance(test) is not None else "NOT ALLOWED"
        print(f"  {note}: {test}: {reason}")
    if not unallowed:
        return 0
    if strict:
        print(f"check_skips: {len(unallowed)} tests skipped that {args.allowed} does not allow "
              f"for '{args.build}': install what they need (tools/install-deps.sh, "
              "tools/install-browser-deps.sh), put ../shared/data next to the checkout, or "
              "list the test with its reason", file=sys.stderr)
        return 1
    print("*" * 78)
    print(f"* {len(unallowed)} TESTS DID NOT RUN (listed above): what they need is missing here.")
    print("* Install it (tools/install-deps.sh, tools/install-browser-deps.sh; ../shared/data")
    print("* next to the checkout for the real-data tests) and rerun: ctest --test-dir build")
    print("*" * 78)
    return 0


if __name__ == "__main__":
    sys.exit(main())
