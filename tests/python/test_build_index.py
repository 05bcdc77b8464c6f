"""build_index is `cwloc-index build`: the same file, byte for byte, for the same flags, its
--json report, and its errors as cwloc.Error."""
import json
import re

import pytest

import cwloc
from conftest import HERZ_OPTIONS, SOURCE, cli_error, run, shared_data, tool


@pytest.fixture(scope="module")
def data():
    found = shared_data("herz_jesu_p25")
    if found is None:
        pytest.skip("shared data 'herz_jesu_p25' not found next to the source tree; skipping")
    return found


@pytest.mark.parametrize("kwargs, flags", [
    ({"seed": 3, "threads": 2}, ["--seed", "3", "--threads", "2"]),
    # The covariance calibration (the default) is compared above; it would build ten more each.
    ({"compact": True, "keypoints": True, "calibration_samples": 0},
     ["--compact", "--keypoints", "--calibration-samples", "0"]),
    ({"clusters": 6, "trees": 3, "calibration_samples": 0},
     ["--clusters", "6", "--trees", "3", "--calibration-samples", "0"]),
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


@pytest.mark.parametrize("kwargs, flags, message", [
    ({"leaf_size": 255}, ["--leaf-size", "255"], "--leaf-size 255: expected 1 to 254"),
    ({"trees": 0}, ["--trees", "0"], "--trees 0: expected 1 to 64"),
    ({"code_bytes": 3}, ["--code-bytes", "3"],
     "--code-bytes 3: expected 0 (full descriptors) or 4, 8, 16, 32 or 64"),
])
def test_out_of_range_is_refused_before_reading(tmp_path, kwargs, flags, message):
    # The model and database do not exist: the range is checked before anything is read.
    out = tmp_path / "x.cwl"
    cli = cli_error([tool("cwloc-index"), "build", "--model", "/nonexistent", "--database",
                     "/nonexistent", "-o", str(out), *flags])
    with pytest.raises(cwloc.BadInputError) as error:
        cwloc.build_index("/nonexistent", "/nonexistent", out, **kwargs)
    assert str(error.value) == cli == message
    assert not out.exists()


def test_keywords_are_the_build_option_table_and_the_cli_flags(tmp_path):
    """Each line of indexer/build_option_table.inc is a keyword and a `cwloc-index build` flag,
    and there are no others, so that the two surfaces cannot drift apart."""
    table = re.findall(r'^CWLOC_BUILD_OPTION\(\s*"([a-z-]+)"',
                       (SOURCE / "indexer" / "build_option_table.inc").read_text(), re.M)
    assert len(table) == 15
    with pytest.raises(cwloc.InvalidArgumentError) as error:
        cwloc.build_index("/nonexistent", "/nonexistent", tmp_path / "x.cwl", nonsense=1)
    accepted = re.fullmatch(r".*unknown option 'nonsense' \(one of (.*)\)", str(error.value))
    assert accepted, str(error.value)
    assert accepted.group(1).split(", ") == [flag.replace("-", "_") for flag in table]
    help_text, _ = run([tool("cwloc-index"), "build", "--help"])
    listed = re.findall(r"^  (?:-[a-z],)?--([a-z-]+)", help_text, re.M)
    assert sorted(listed) == sorted(table + ["help", "model", "database", "output", "json"])
    assert all(name.replace("-", "_") in cwloc.build_index.__doc__ for name in table)


def test_apply_index_delta_gives_the_updates_bytes(data, tmp_path):
    """cwloc.apply_index_delta is `cwloc-index apply`: the bytes `update` wrote; another
    parent is refused as bad input and nothing is written."""
    model, database = data / "mapping_model" / "bin", data / "database.db"
    index, updated, delta = tmp_path / "a.cwl", tmp_path / "b.cwl", tmp_path / "b.cwld"
    cwloc.build_index(model, database, index, calibration_samples=0)
    run([tool("cwloc-index"), "update", "--index", str(index), "--model", str(model),
         "--database", str(database), "-o", str(updated), "--delta", str(delta)])
    cwloc.apply_index_delta(index, delta, tmp_path / "applied.cwl", threads=1)
    assert (tmp_path / "applied.cwl").read_bytes() == updated.read_bytes()
    with pytest.raises(cwloc.BadInputError, match="made for the index with checksum"):
        cwloc.apply_index_delta(updated, delta, tmp_path / "wrong.cwl")
    assert not (tmp_path / "wrong.cwl").exists()

