"""Bad input raises cwloc.Error subclasses carrying the library's message (cwloc-localize's for
the same input); wrong Python types raise TypeError / ValueError saying what was expected."""
import shutil

import numpy as np
import pytest

import cwloc
from conftest import HERZ_OPTIONS, cli_error, tool


def features_args(index, golden, nb=None):
    _, camera, features = golden[1][0]
    args = [tool("cwloc-localize"), "--index", str(index), "--features", str(features),
            "--camera", camera, "-q"]
    return args + (["--nb", str(nb)] if nb is not None else [])


def query(golden):
    _, camera, features = golden[1][0]
    return (*cwloc.read_feature_file(features), camera)


def test_hierarchy():
    assert issubclass(cwloc.Error, RuntimeError)
    assert issubclass(cwloc.InvalidArgumentError, cwloc.Error)
    assert issubclass(cwloc.InvalidArgumentError, ValueError)
    assert issubclass(cwloc.BadInputError, cwloc.Error)
    assert issubclass(cwloc.OutOfMemoryError, MemoryError)
    assert issubclass(cwloc.InternalError, cwloc.Error)


def test_missing_index(golden, tmp_path):
    missing = tmp_path / "missing.cwl"
    with pytest.raises(cwloc.BadInputError) as error:
        cwloc.Localizer.open(missing)
    assert error.value.code == cwloc.ErrorCode.BAD_INPUT
    assert str(error.value) == cli_error(features_args(missing, golden))


def test_corrupt_index(golden, tmp_path):
    truncated = tmp_path / "truncated.cwl"
    truncated.write_bytes(golden[0].read_bytes()[:1000])
    with pytest.raises(cwloc.BadInputError) as error:
        cwloc.Localizer.open(truncated)
    assert str(error.value) == cli_error(features_args(truncated, golden))
    # A flipped byte in a section: found by verify (every checksum).
    flipped = tmp_path / "flipped.cwl"
    data = bytearray(golden[0].read_bytes())
    data[len(data) // 2] ^= 0xFF
    flipped.write_bytes(bytes(data))
    with pytest.raises(cwloc.BadInputError, match="checksum"):
        cwloc.Localizer.open(flipped, verify=True)


def test_unknown_option(golden, golden_localizer):
    with pytest.raises(cwloc.InvalidArgumentError) as error:
        golden_localizer.localize_features(*query(golden), nb2=3)
    assert str(error.value) == "unknown option 'nb2'"
    assert error.value.code == cwloc.ErrorCode.INVALID_ARGUMENT
    with pytest.raises(ValueError):  # InvalidArgumentError is a ValueError too
        cwloc.Options(nb2=3)


def test_option_out_of_range_has_the_clis_message(golden, golden_localizer):
    with pytest.raises(cwloc.InvalidArgumentError) as error:
        golden_localizer.localize_features(*query(golden), nb=0)
    assert str(error.value) == cli_error(features_args(golden[0], golden, nb=0))
    assert str(error.value) == "--nb 0: expected at least 1"
    with pytest.raises(cwloc.InvalidArgumentError, match="matcher"):
        cwloc.Options(matcher="nearest")
    with pytest.raises(TypeError, match="nb"):
        cwloc.Options(nb=[1])


def test_descriptors_and_keypoints(golden, golden_localizer):
    keypoints, descriptors, camera = query(golden)
    with pytest.raises(TypeError, match="descriptors: expected dtype uint8.*float32"):
        golden_localizer.localize_features(keypoints, descriptors.astype(np.float32), camera)
    with pytest.raises(ValueError, match=r"descriptors: expected shape \(N, 128\), got \(149, 64\)"):
        golden_localizer.localize_features(keypoints, descriptors[:, :64], camera)
    with pytest.raises(ValueError, match=r"keypoints: expected shape \(N, 2\)"):
        golden_localizer.localize_features(keypoints[:, :1], descriptors, camera)
    with pytest.raises(TypeError, match="keypoints: expected a float array"):
        golden_localizer.localize_features(keypoints.astype(np.int32), descriptors, camera)
    with pytest.raises(ValueError, match="149 keypoints but 148 descriptors"):
        golden_localizer.localize_features(keypoints, descriptors[:-1], camera)


def test_cameras(golden, golden_localizer):
    keypoints, descriptors, _ = query(golden)
    with pytest.raises(cwloc.InvalidArgumentError, match="PINHOLE takes 4 parameters, got 1$"):
        golden_localizer.localize_features(keypoints, descriptors, "PINHOLE 1024 768 900")
    with pytest.raises(ValueError, match="expected 'MODEL WIDTH HEIGHT PARAMS...'"):
        cwloc.Camera.from_string("PINHOLE wide")
    with pytest.raises(TypeError, match="camera: expected a cwloc.Camera"):
        golden_localizer.localize_features(keypoints, descriptors, 42)
    with pytest.raises(ValueError, match="calibration"):
        cwloc.Camera("PINHOLE", 10, 10, [1, 1, 5, 5], calibration="exact")


def test_photo_errors(herz, herz_localizer, tmp_path):
    data, index = herz
    photo = data / "query_images" / "0012.jpg"
    broken = tmp_path / "broken.jpg"
    broken.write_bytes(photo.read_bytes()[:5000])
    cli = cli_error([tool("cwloc-localize"), "--index", str(index), "--image", str(broken), "-q"])
    with pytest.raises(cwloc.BadInputError) as error:
        herz_localizer.localize_photo(broken, **HERZ_OPTIONS)
    assert str(error.value) == cli
    with pytest.raises(cwloc.BadInputError, match="corrupt JPEG"):
        herz_localizer.localize_photo(broken.read_bytes(), **HERZ_OPTIONS)
    with pytest.raises(cwloc.BadInputError):
        herz_localizer.localize_photo(b"not a photo")
    wrong = "SIMPLE_RADIAL 640 1024 1375 768 512 0"
    cli = cli_error([tool("cwloc-localize"), "--index", str(index), "--image", str(photo),
                     "--camera", wrong, "-q"])
    with pytest.raises(cwloc.InvalidArgumentError) as error:
        herz_localizer.localize_photo(str(photo), wrong, **HERZ_OPTIONS)
    assert str(error.value) == cli
    with pytest.raises(TypeError, match="photo: expected a str or os.PathLike"):
        herz_localizer.localize_photo(12)


def test_grey_image_errors(golden_localizer):
    camera = cwloc.Camera.unknown(64, 48)
    with pytest.raises(TypeError, match="image: expected dtype uint8"):
        golden_localizer.localize_grey(np.zeros((48, 64), np.float32), camera)
    with pytest.raises(ValueError, match=r"image: expected shape \(height, width\)"):
        golden_localizer.localize_grey(np.zeros((48, 64, 3), np.uint8), camera)
    # A camera of another size than the image: the library's check.
    with pytest.raises(cwloc.InvalidArgumentError):
        golden_localizer.localize_grey(np.zeros((48, 64), np.uint8), cwloc.Camera.unknown(32, 48))


def test_prior_on_an_index_without_georeference(golden, golden_localizer):
    with pytest.raises(cwloc.InvalidArgumentError, match="georeferenced"):
        golden_localizer.localize_features(*query(golden), prior_position=(47.0, 8.0, 100.0))
    with pytest.raises(ValueError, match="prior_gravity"):
        golden_localizer.localize_features(*query(golden), prior_gravity=(0, 1))
