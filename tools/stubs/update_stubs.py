#!/usr/bin/env python3
"""Writes the attributes of python/cwloc/__init__.pyi's result classes from the result types'
descriptions (results/describe.h), as the built module reports them
(cwloc._cwloc._described_classes()): each described class's attribute lines, right after its
`class NAME:` line, are the description's fields in order; a class the stubs lack is added at the
end. Methods written by hand follow the attributes and are kept.

Usage: PYTHONPATH=build/python tools/stubs/update_stubs.py [--check] [STUBS]
--check writes nothing and exits 1, printing a diff, when the stubs are not what the descriptions
make (tests/python/test_stubs.py runs it).
"""
import argparse
import difflib
import re
import sys
from pathlib import Path

ATTRIBUTE = re.compile(r"^    [A-Za-z_][A-Za-z0-9_]*: ")


def attribute_lines(fields):
    lines = []
    for name, stub_type, doc, *_ in fields:
        line = f"    {name}: {stub_type}"
        if doc:
            line += f"  # {doc}"
        lines.append(line)
    return lines


def updated(text, classes):
    lines = text.splitlines()
    for name, help_text, fields in classes:
        header = f"class {name}:"
        generated = attribute_lines(fields)
        if header in lines:
            start = lines.index(header) + 1
            end = start
            while end < len(lines) and ATTRIBUTE.match(lines[end]):
                end += 1
            lines[start:end] = generated
        else:
            lines += ["", f"# {help_text}", header] + (generated or ["    ..."])
    return "\n".join(lines) + "\n"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true")
    parser.add_argument("stubs", nargs="?",
                        default=Path(__file__).resolve().parents[2] / "python/cwloc/__init__.pyi")
    args = parser.parse_args()
    import cwloc._cwloc as module
    path = Path(args.stubs)
    text = path.read_text()
    new = updated(text, module._described_classes())
    if new == text:
        return 0
    if args.check:
        sys.stdout.writelines(difflib.unified_diff(text.splitlines(True), new.splitlines(True),
                                                   str(path), "from the descriptions"))
        print(f"{path} is stale: run PYTHONPATH=build/python {sys.argv[0]} {path}")
        return 1
    path.write_text(new)
    print(f"{path}: attributes written from the descriptions")
    return 0


if __name__ == "__main__":
    sys.exit(main())
