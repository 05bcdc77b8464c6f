#!/usr/bin/env python3
"""Checks that every project header a target includes belongs to a library it links, and that
docs/architecture.md's library table lists exactly the CMake libraries, folders and links.

Reads the cwloc_add_library / cwloc_add_executable / cwloc_add_test / cwloc_add_python_module
calls of every CMakeLists.txt, assigns each header to the library that compiles the source files of its
folder (a header-only INTERFACE library lists its headers as SRCS), and follows PUBLIC links
transitively (PRIVATE links count for the target itself only). Prints one line per violation
and exits 1; exits 0 when the layering holds.

Usage: tools/check_layering.py [SOURCE_DIR]
"""
import re
import sys
from pathlib import Path

CALL = re.compile(r"\b(cwloc_add_library|cwloc_add_executable|cwloc_add_test|cwloc_add_python_module)\(\s*([A-Za-z0-9_]+)(.*?)\)\s*$",
                  re.S | re.M)
SET = re.compile(r"\bset\(\s*([A-Z0-9_]+)\s+([^)]*)\)")
APPEND = re.compile(r"\blist\(\s*APPEND\s+([A-Z0-9_]+)\s+([^)]*)\)")
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
KEYWORDS = {"SRCS", "PUBLIC_LINK", "PRIVATE_LINK", "LINK", "OUTPUT"}
FLAGS = {"SHARED", "INTERFACE"}  # cwloc_add_library's options, before the keywords


def parse_calls(root):
    """Yields (kind, name, folder, {keyword: [words]}) for each target declaration."""
    for cmake in sorted(root.rglob("CMakeLists.txt")):
        if any(part.startswith("build") or part == ".git" for part in cmake.relative_to(root).parts):
            continue
        text = re.sub(r"#.*", "", cmake.read_text())
        variables = {}
        for name, words in SET.findall(text):
            variables.setdefault(name, []).extend(words.split())
        for name, words in APPEND.findall(text):
            variables.setdefault(name, []).extend(words.split())
        for kind, name, body in CALL.findall(text):
            args, key = {}, None
            for word in body.split():
                for value in expand(word, variables):
                    if value in FLAGS and key is None:
                        args.setdefault("FLAGS", []).append(value)
                    elif value in KEYWORDS:
                        key = value
                        args.setdefault(key, [])
                    elif key:
                        args[key].append(value)
            yield kind, name, cmake.parent, args


def expand(word, variables):
    match = re.fullmatch(r"\$\{([A-Z0-9_]+)\}", word)
    if match and match.group(1) in variables:
        return [v for w in variables[match.group(1)] for v in expand(w, variables)]
    return [word]


def main():
    root = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent.parent).resolve()
    targets = {}
    for kind, name, folder, args in parse_calls(root):
        sources = []
        for src in args.get("SRCS", []):
            path = Path(src.replace("${PROJECT_SOURCE_DIR}", str(root)))
            sources.append((path if path.is_absolute() else folder / path).resolve())
        targets[name] = {
            "kind": kind,
            "sources": sources,
            "public": args.get("PUBLIC_LINK", []) + args.get("LINK", []),
            "private": args.get("PRIVATE_LINK", []),
            "interface": "INTERFACE" in args.get("FLAGS", []),
        }

    # A header belongs to the library (or Python module: python/src/) whose source of the same
    # stem, else of the same folder, it sits beside.
    owner_by_stem, owner_by_folder = {}, {}
    for name, target in targets.items():
        if target["kind"] not in ("cwloc_add_library", "cwloc_add_python_module"):
            continue
        for src in target["sources"]:
            owner_by_stem[src.with_suffix("")] = name
            owner_by_folder.setdefault(src.parent, name)

    def owner(header):
        # A library's public headers may sit in its folder's include/ tree (api/include/cwloc/).
        folders = [header.parent] + [p.parent for p in header.parents if p.name == "include"]
        return owner_by_stem.get(header.with_suffix("")) or next(
            (owner_by_folder[f] for f in folders if f in owner_by_folder), None)

    def closure(name, seen=None):
        seen = set() if seen is None else seen
        for dep in targets.get(name, {}).get("public", []):
            if dep in targets and dep not in seen:
                seen.add(dep)
                closure(dep, seen)
        return seen

    def allowed(name, include_private):
        result = {name} | closure(name)
        if include_private:
            for dep in targets[name]["private"]:
                if dep in targets:
                    result |= {dep} | closure(dep)
        return result

    violations = []

    # A header-only library has headers alone and nothing private to link.
    for name, target in targets.items():
        if target["interface"]:
            if not target["sources"]:
                violations.append(f"{name}: an INTERFACE library lists its headers as SRCS")
            for src in target["sources"]:
                if src.suffix != ".h":
                    violations.append(f"{name}: INTERFACE library with a non-header source {src.relative_to(root)}")
            if target["private"]:
                violations.append(f"{name}: INTERFACE library with a PRIVATE_LINK")

    def check(path, target_name, include_private):
        for include in INCLUDE.findall(path.read_text(errors="replace")):
            header = (root / include).resolve()
            if not header.exists() or include.startswith(("tests/", "fuzz/")):
                continue  # generated, system-like or test and fuzz harness headers
            lib = owner(header)
            if lib and lib not in allowed(target_name, include_private):
                violations.append(f"{path.relative_to(root)} ({target_name}) includes {include} "
                                  f"of {lib}, which {target_name} does not link")

    for name, target in targets.items():
        for src in target["sources"]:
            if src.exists() and "tests" not in src.relative_to(root).parts[:1]:
                check(src, name, include_private=True)
    for header in sorted(root.rglob("*.h")):
        rel = header.relative_to(root)
        if rel.parts[0] in ("tests", "fuzz", ".git") or rel.parts[0].startswith("build"):
            continue
        lib = owner(header.resolve())
        if lib:
            check(header.resolve(), lib, include_private=False)
        else:
            violations.append(f"{rel}: in no library's folder")

    violations += check_architecture_table(root, targets)

    for line in sorted(set(violations)):
        print(line)
    if violations:
        print(f"check_layering: {len(set(violations))} violation(s)", file=sys.stderr)
        return 1
    print(f"check_layering: OK ({sum(t['kind'] == 'cwloc_add_library' for t in targets.values())} libraries)")
    return 0


def check_architecture_table(root, targets):
    """Rows `| `lib` | `folder/` | `link`, `link` (private) | used by |` against CMake."""
    doc = root / "docs" / "architecture.md"
    rows = {}
    for line in doc.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 3 and re.fullmatch(r"`cwloc_\w+`", cells[0]):
            rows[cells[0].strip("`")] = (cells[1].strip("`"), set(re.findall(r"`([^`]+)`", cells[2])))
    problems = []
    libraries = {n: t for n, t in targets.items() if t["kind"] == "cwloc_add_library"}
    for name in sorted(set(libraries) - set(rows)):
        problems.append(f"docs/architecture.md: library {name} is missing from the table")
    for name in sorted(set(rows) - set(libraries)):
        problems.append(f"docs/architecture.md: {name} is in the table but no CMake library")
    for name in sorted(set(rows) & set(libraries)):
        folder, links = rows[name]
        folders = {str(src.parent.relative_to(root)) + "/" for src in libraries[name]["sources"]}
        if folders != {folder}:
            problems.append(f"docs/architecture.md: {name} is in {sorted(folders)}, the table says {folder}")
        cmake_links = set(libraries[name]["public"] + libraries[name]["private"])
        if links != cmake_links:
            problems.append(f"docs/architecture.md: {name} links {sorted(cmake_links)}, the table says {sorted(links)}")
    return problems


if __name__ == "__main__":
    sys.exit(main())
