"""build_index is `cwloc-index build`: the same file, byte for byte, for the same flags, its
--json report, and its errors as cwloc.Error."""
import json

import pytest

import cwloc
from conftest import HERZ_OPTIONS, cli_error, run, shared_data, tool


@pytest.fixture(scope="module")
def data():
    found = shared_data("herz_jesu_p25")
    if found is None:
        pytest.skip("shared data 'herz_jesu_p25' not found next to the source tree; skipping")
    return found


@pytest.mark.parametrize("kwargs, flags", [
    ({"seed": 3, "threads": 2}, ["--seed", "3", "--threads", "2"]),
    ({"compact": True, "keypoints": True}, ["--compact", "--keypoints"]),
    ({"clusters": 6, "trees": 3}, ["--clusters", "6", "--trees", "3"]),
])
def test_same_file_as_the_cli(data, tmp_path, kwargs, flags):
    model, database = data / "mapping_model" / "bin", data / "database.db"
    by_cli, by_python = tmp_path / "cli.cwl", tmp_path / "python.cwl"
    out, _ = run([tool("cwloc-index"), "build", "--model", str(model), "--database",
                  str(database), "-o", str(by_cli), "--json", *flags])
    report = cwloc.build_index(model, database, by_python, **kwargs)
    assert by_python.read_bytes() == by_cli.read_bytes()
    cli = json.loads(out)
    assert report["counts"] == cli["counts"]
    assert report["file_bytes"] == cli["file_bytes"] == by_python.stat().st_size
    assert report["output"] == str(by_python)
    assert set(report["seconds"]) == set(cli["seconds"])


def test_built_index_localizes(data, tmp_path):
    index = tmp_path / "herz.cwl"
    cwloc.build_index(str(data / "mapping_model" / "bin"), data / "database.db", index, seed=1)
    result = cwloc.Localizer.open(index, verify=True).localize_photo(
        data / "query_images" / "0007.jpg", **HERZ_OPTIONS)
    assert result.success


def test_errors(data, tmp_path):
    missing = tmp_path / "no_model"
    out = tmp_path / "x.cwl"
    cli = cli_error([tool("cwloc-index"), "build", "--model", str(missing), "--database",
                     str(data / "database.db"), "-o", str(out)])
    with pytest.raises(cwloc.BadInputError) as error:
        cwloc.build_index(missing, data / "database.db", out)
    assert str(error.value) == cli
    with pytest.raises(cwloc.InvalidArgumentError, match="unknown option 'tree'"):
        cwloc.build_index(data / "mapping_model" / "bin", data / "database.db", out, tree=2)
    with pytest.raises(TypeError, match="seed: expected a whole number"):
        cwloc.build_index(data / "mapping_model" / "bin", data / "database.db", out, seed=1.5)
    with pytest.raises(cwloc.BadInputError, match="--cluster-file excludes --clusters"):
        cwloc.build_index(data / "mapping_model" / "bin", data / "database.db", out,
                          clusters=3, cluster_file="c.txt")
