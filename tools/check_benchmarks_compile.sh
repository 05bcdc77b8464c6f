#!/usr/bin/env bash
# The benchmarks (bench/) compile against the current code: each of their files through the
# compiler's front end (-fsyntax-only, templates instantiated, no code generated) with the
# command a build would use, from BUILD's compile_commands.json. The README's test command builds
# only the tests and the tools they run; this keeps the benchmarks from rotting at a third of
# their compile time. Link errors are not caught (`cmake --build BUILD` links them).
#
# Usage: tools/check_benchmarks_compile.sh BUILD   (a configured build with CWLOC_BUILD_BENCHMARKS)
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: tools/check_benchmarks_compile.sh BUILD" >&2; exit 2; }
build=$(realpath "$1")
[ -f "$build/compile_commands.json" ] || { echo "$build: no compile_commands.json" >&2; exit 2; }
commands=$(mktemp)
trap 'rm -f "$commands"' EXIT
python3 - "$build/compile_commands.json" >"$commands" <<'PY'
import json, shlex, sys
for entry in json.load(open(sys.argv[1])):
    if "/bench/" not in entry["file"]:  # bench/x.cc, or build/bench/.../Unity/unity_0_cxx.cxx
        continue
    words = shlex.split(entry["command"])
    out = words.index("-o")
    del words[out:out + 2]
    for flag in ("-MD", "-MMD"):
        while flag in words:
            words.remove(flag)
    for flag in ("-MF", "-MT"):
        if flag in words:
            i = words.index(flag)
            del words[i:i + 2]
    print("cd " + shlex.quote(entry["directory"]) + " && " + shlex.join(words + ["-fsyntax-only"]))
PY
count=$(wc -l <"$commands")
[ "$count" -gt 0 ] || { echo "$build: no benchmark in compile_commands.json" >&2; exit 2; }
tr '\n' '\0' <"$commands" | xargs -0 -P "$(nproc)" -I{} bash -c {}
echo "check_benchmarks_compile: $count files of bench/ compile"
