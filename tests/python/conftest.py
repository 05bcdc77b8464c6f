"""What the Python tests share: the source tree, the tools to compare with, the golden index
and, as the C++ API tests have it, ../shared/data/herz_jesu_p25 with an index built once per
run (its tests skip when the data set is absent). CWLOC_SOURCE_DIR, CWLOC_BIN_DIR and
CWLOC_SHARED_DATA override the locations, as for the C++ tests."""
import json
import os
import subprocess
from pathlib import Path

import pytest

SOURCE = Path(os.environ.get("CWLOC_SOURCE_DIR", Path(__file__).resolve().parents[2]))
BIN = Path(os.environ.get("CWLOC_BIN_DIR", SOURCE / "build" / "bin"))
GOLDEN = SOURCE / "tests" / "data" / "golden"
# As the data set's README says it was extracted.
HERZ_OPTIONS = {"max_image_size": 1600, "max_features": 6000}
HERZ_FLAGS = ["--max-image-size", "1600", "--max-features", "6000"]


def tool(name):
    return str(BIN / name)


def run(args, expect=0):
    """Runs a tool; returns (stdout, stderr) and checks its exit code."""
    done = subprocess.run(args, capture_output=True, text=True)
    assert done.returncode == expect, f"{args}: exit {done.returncode}\n{done.stderr}"
    return done.stdout, done.stderr


def cli_error(args):
    """The message a tool prints for bad input ('cwloc-localize: error: MESSAGE')."""
    _, stderr = run(args, expect=2)
    lines = [l for l in stderr.splitlines() if ": error: " in l]
    assert lines, stderr
    return lines[-1].split(": error: ", 1)[1]


def read_jsonl(path):
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def shared_data(name):
    roots = [Path(os.environ["CWLOC_SHARED_DATA"])] if "CWLOC_SHARED_DATA" in os.environ else []
    roots.append(SOURCE / ".." / "shared" / "data")
    for root in roots:
        if (root / name).is_dir():
            return (root / name).resolve()
    return None


@pytest.fixture(scope="session")
def golden():
    """(index, [(name, camera text, feature file)]) of the golden 1.0 city."""
    queries = []
    for line in (GOLDEN / "index-1.0-queries" / "queries_gt.txt").read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        fields = line.split()
        queries.append((fields[0], " ".join(fields[8:]),
                        GOLDEN / "index-1.0-queries" / (fields[0] + ".txt")))
    return GOLDEN / "index-1.0.cwl", queries


@pytest.fixture(scope="session")
def golden_localizer(golden):
    import cwloc
    return cwloc.Localizer.open(golden[0])


@pytest.fixture(scope="session")
def herz(tmp_path_factory):
    """(data folder, index built by cwloc-index with default options)."""
    data = shared_data("herz_jesu_p25")
    if data is None:
        pytest.skip("shared data 'herz_jesu_p25' not found next to the source tree; skipping")
    index = tmp_path_factory.mktemp("herz") / "herz_jesu_p25.cwl"
    run([tool("cwloc-index"), "build", "--model", str(data / "mapping_model" / "bin"),
         "--database", str(data / "database.db"), "-o", str(index)])
    return data, index


@pytest.fixture(scope="session")
def herz_localizer(herz):
    import cwloc
    return cwloc.Localizer.open(herz[1])
