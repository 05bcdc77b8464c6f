"""cwloc.Tracker is cwloc-localize --sequence: the same modes and poses, bit for bit, on the
first frames of a real phone video (../shared/data/fox_video, skipped without it), from its
photos at fast frame settings."""
from pathlib import Path

import pytest

import cwloc
from conftest import read_jsonl, run, shared_data, tool

FRAME_OPTIONS = {"max_image_size": 1600, "first_octave": 0, "max_features": 4000}
FRAME_FLAGS = ["--max-image-size", "1600", "--first-octave", "0", "--max-features", "4000"]


@pytest.fixture(scope="module")
def fox(tmp_path_factory):
    data = shared_data("fox_video")
    if data is None:
        pytest.skip("shared data 'fox_video' not found next to the source tree; skipping")
    index = tmp_path_factory.mktemp("fox") / "fox_video.cwl"
    run([tool("cwloc-index"), "build", "--model", str(data / "mapping_model" / "bin"),
         "--database", str(data / "database.db"), "-o", str(index)])
    return data, index


def test_the_tracker_is_the_cli_sequence(fox, tmp_path):
    data, index = fox
    frames = [line.split(maxsplit=1)
              for line in (data / "queries_with_intrinsics.txt").read_text().splitlines()[:6]]
    (tmp_path / "frames.txt").write_text("".join(f"{name} {camera}\n" for name, camera in frames))
    run([tool("cwloc-localize"), "--index", str(index), "--image-list", str(tmp_path / "frames.txt"),
         "--image-dir", str(data / "query_images"), "--sequence", "-q",
         "-o", str(tmp_path / "cli.jsonl")] + FRAME_FLAGS)
    records = read_jsonl(tmp_path / "cli.jsonl")
    tracker = cwloc.Tracker(cwloc.Localizer.open(index), **FRAME_OPTIONS)
    modes = []
    for (name, camera), record in zip(frames, records):
        result = tracker.track_photo(data / "query_images" / name, camera)
        assert result.success, name
        assert result.tracking.mode == record["tracking"]["mode"], name
        # The API names a photo by its path, the list by the name it gives.
        predicted_from = result.tracking.predicted_from
        assert (predicted_from and Path(predicted_from).name) == record["tracking"]["predicted_from"]
        assert result.rotation.tolist() == record["pose"]["qvec"], name
        assert result.translation.tolist() == record["pose"]["tvec"], name
        assert result.to_dict()["tracking"]["mode"] == result.tracking.mode
        modes.append(result.tracking.mode)
    assert len(records) == len(frames)
    assert modes[0] == "relocalized" and modes.count("tracked") >= 2, modes
    # A query alone has no tracking; reset starts from scratch.
    assert cwloc.Localizer.open(index).localize_photo(
        data / "query_images" / frames[0][0], frames[0][1], **FRAME_OPTIONS).tracking is None
    tracker.reset()
    again = tracker.track_photo(data / "query_images" / frames[1][0], frames[1][1])
    assert again.tracking.mode == "relocalized" and again.tracking.predicted_from is None
    # VIO's motion since the previous frame: ((w, x, y, z), (tx, ty, tz)), optionally with its
    # sigmas (degrees, metres); anything else is a TypeError naming the form.
    moved = tracker.track_photo(data / "query_images" / frames[2][0], frames[2][1],
                                motion=((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0)))
    assert moved.success and moved.tracking.predicted_from is not None
    sure = tracker.track_photo(data / "query_images" / frames[2][0], frames[2][1],
                               motion=((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (2.0, 0.1)))
    assert sure.success
    with pytest.raises(TypeError, match=r"motion: expected \(\(w, x, y, z\), \(tx, ty, tz\)\[, "
                       r"\(sigma_rotation_deg, sigma_position\)\]\) or None"):
        tracker.track_photo(data / "query_images" / frames[3][0], frames[3][1], motion=(1, 2))
    with pytest.raises(ValueError, match=r"motion: the sigmas are finite and at least 0"):
        tracker.track_photo(data / "query_images" / frames[3][0], frames[3][1],
                            motion=((1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0), (-1.0, 0.1)))
    # The frame's time in seconds, or None; anything else is a TypeError.
    timed = tracker.track_photo(data / "query_images" / frames[3][0], frames[3][1], timestamp=1.5)
    assert timed.success and timed.tracking.predicted_from is not None
    with pytest.raises(TypeError, match=r"timestamp: expected a number of seconds or None"):
        tracker.track_photo(data / "query_images" / frames[4][0], frames[4][1], timestamp="now")
