"""cwloc.dask.localize_many on a local cluster of 2 worker processes gives the records a single
process gives, in order, with each worker opening the index once."""
import shutil

import pytest

import cwloc
import cwloc.dask
from conftest import HERZ_OPTIONS

distributed = pytest.importorskip("distributed")

# The JSON fields that are wall-clock times, not results.
TIMES = ("times_ms",)


def without_times(record):
    return {k: v for k, v in record.items() if k not in TIMES}


@pytest.fixture(scope="module")
def client():
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def test_two_workers_give_the_single_process_records_in_order(herz, client, tmp_path):
    data, index = herz
    photos = sorted(str(p) for p in (data / "query_images").glob("*.jpg"))
    assert len(photos) == 5
    broken = tmp_path / "broken.jpg"
    broken.write_bytes(b"\xff\xd8\xff\xe0 not a JPEG")
    queries = photos[:2] + [str(broken)] + photos[2:]
    camera = cwloc.Camera.from_string(
        (data / "queries_with_intrinsics.txt").read_text().split("\n")[0].split(" ", 1)[1])

    records = cwloc.dask.localize_many(client, index, queries, camera=camera, **HERZ_OPTIONS)

    assert [r["name"] for r in records] == queries
    localizer = cwloc.Localizer.open(index)
    for query, record in zip(queries, records):
        if query == str(broken):
            assert record["success"] is False
            assert str(broken) in record["error"]
            with pytest.raises(cwloc.BadInputError) as raised:
                localizer.localize_photo(query, camera=camera, **HERZ_OPTIONS)
            assert record["error"] == str(raised.value)
            continue
        single = localizer.localize_photo(query, camera=camera, **HERZ_OPTIONS).to_dict()
        single["name"] = query
        assert record["success"] and record["covariance"]["position_radius95"] > 0
        assert without_times(record) == without_times(single)

    # Each worker process opened the index once, on its first photo, and kept it.
    opened = client.run(lambda: sorted(cwloc.dask._opened))
    assert len(opened) == 2
    assert all(paths == [str(index)] for paths in opened.values())


def test_names_bytes_and_bad_arguments(golden, herz, client):
    data, index = herz
    photo = data / "query_images" / "0002.jpg"
    (record,) = cwloc.dask.localize_many(client, index, [photo.read_bytes()], names=["q"],
                                         **HERZ_OPTIONS)
    assert record["name"] == "q" and record["success"]
    # A bad option fails the call at once, with the library's message.
    with pytest.raises(cwloc.InvalidArgumentError, match="^--nb 0: expected at least 1$"):
        cwloc.dask.localize_many(client, index, [str(photo)], nb=0)
    with pytest.raises(cwloc.InvalidArgumentError, match="^unknown option 'focal'$"):
        cwloc.dask.localize_many(client, index, [str(photo)], focal=1375.77)
    with pytest.raises(ValueError, match="names: 1 names for 2 photos"):
        cwloc.dask.localize_many(client, index, [str(photo)] * 2, names=["q"])
