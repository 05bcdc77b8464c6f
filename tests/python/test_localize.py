"""The module gives cwloc-localize's poses bit for bit, as typed results with numpy arrays."""
import json
import os
from pathlib import Path

import numpy as np
import pytest

import cwloc
from conftest import GOLDEN, HERZ_FLAGS, HERZ_OPTIONS, SOURCE, read_jsonl, run, tool


def test_version_is_the_librarys():
    out, _ = run([tool("cwloc-localize"), "--version"])
    assert cwloc.__version__ == cwloc.version()
    assert out.split()[-1] == cwloc.__version__


def test_info(golden, golden_localizer):
    info = golden_localizer.info()
    assert isinstance(info, cwloc.IndexInfo)
    # tests/data/README.md's counts of index-1.0.cwl
    assert (info.format_version, info.num_images, info.num_points, info.num_views) == \
        ("1.0", 26, 718, 1707)
    assert info.path == str(golden[0]) and not info.georeferenced


def test_features_give_the_clis_poses(golden, golden_localizer, tmp_path):
    index, queries = golden
    for name, camera, features in queries:
        out = tmp_path / (name + ".jsonl")
        run([tool("cwloc-localize"), "--index", str(index), "--features", str(features),
             "--camera", camera, "-q", "-o", str(out)])
        (cli,) = read_jsonl(out)
        keypoints, descriptors = cwloc.read_feature_file(features)
        result = golden_localizer.localize_features(keypoints, descriptors, camera)
        assert cli["success"] and result.success, name
        assert result.rotation.tolist() == cli["pose"]["qvec"]
        assert result.translation.tolist() == cli["pose"]["tvec"]
        assert result.num_inliers == cli["num_inliers"]
        assert result.correspondences == cli["matches"]["correspondences"]
        # The same input as a Camera object and as float64 keypoints: the same pose.
        again = golden_localizer.localize_features(
            keypoints.astype(np.float64), descriptors, cwloc.Camera.from_string(camera))
        assert again.rotation.tolist() == cli["pose"]["qvec"]


def test_result_fields(golden, golden_localizer):
    _, queries = golden
    name, camera, features = queries[0]
    result = golden_localizer.localize_features(*cwloc.read_feature_file(features), camera,
                                                ranked_images=3)
    assert result.success
    assert result.rotation.shape == (4,) and result.rotation.dtype == np.float64
    r = result.cam_from_world
    assert r.shape == (3, 3)
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-12)
    np.testing.assert_allclose(result.center, -r.T @ result.translation, atol=1e-9)
    inliers = result.inliers
    assert len(inliers) == result.num_inliers
    assert inliers.feature.dtype == np.uint32 and inliers.point.dtype == np.uint32
    assert inliers.keypoint.shape == (result.num_inliers, 2)
    assert inliers.keypoint.dtype == np.float32
    assert inliers.xyz.shape == (result.num_inliers, 3) and inliers.xyz.dtype == np.float64
    # Inliers reproject within --max-error through the reported SIMPLE_RADIAL camera and pose.
    f, cx, cy, k = result.camera.params
    cam = inliers.xyz @ r.T + result.translation
    assert (cam[:, 2] > 0).all()
    xy = cam[:, :2] / cam[:, 2:]
    pixels = f * xy * (1 + k * (xy**2).sum(axis=1, keepdims=True)) + [cx, cy]
    errors = np.linalg.norm(pixels - inliers.keypoint, axis=1)
    assert errors.max() <= cwloc.default_options()["max_error"]
    assert len(result.ranked_images) == 3
    assert all(isinstance(i, cwloc.RankedImage) and i.votes > 0 for i in result.ranked_images)
    given = cwloc.Camera.from_string(camera)
    assert (result.camera.model, result.camera.width, result.camera.height, result.camera.params,
            result.camera.calibration) == (given.model, given.width, given.height, given.params,
                                           given.calibration)
    assert result.camera.intrinsics_source == "camera-option"
    assert not result.camera.focal_estimated and result.camera.distortion.fit == "given"
    assert set(result.times.to_dict()) >= {"forward_knn", "pose", "total"}
    assert result.geo is None
    assert result.priors.position is None and result.priors.gravity is None
    record = result.to_dict()
    assert record == json.loads(result.json)
    assert record["pose"]["qvec"] == result.rotation.tolist()
    assert record["num_inliers"] == result.num_inliers


def test_covariance_when_the_library_gives_one(golden, golden_localizer):
    _, queries = golden
    _, camera, features = queries[0]
    result = golden_localizer.localize_features(*cwloc.read_feature_file(features), camera)
    cov = result.covariance
    assert cov is not None  # every localized result has one
    assert cov.pose.shape == (6, 6)
    np.testing.assert_allclose(cov.pose, cov.pose.T, rtol=1e-9, atol=1e-15)
    assert cov.position_radius95 > 0
    assert cov.enu_position is None  # the golden 1.0 city is not georeferenced


def test_covariance_in_metres_on_a_georeferenced_index():
    """On the georeferenced golden city the centre's covariance comes in metres east-north-up
    too: the model's block rotated and scaled by the georeference, so every query's radius in
    metres is its radius in model units times the same scale, near the city's true one."""
    folder = GOLDEN / "index-1.1-queries"
    localizer = cwloc.Localizer.open(GOLDEN / "index-1.1.cwl")
    true_scale = float(next(line.split()[1] for line in
                            (folder / "scale_to_metres.txt").read_text().splitlines()
                            if line.startswith("scale ")))
    scales = []
    for line in (folder / "queries_gt.txt").read_text().splitlines():
        if line.startswith("#") or not line.strip():
            continue
        fields = line.split()
        result = localizer.localize_features(
            *cwloc.read_feature_file(folder / (fields[0] + ".txt")), " ".join(fields[8:]))
        assert result.success, result.failure_reason
        cov = result.covariance
        assert cov.enu_position.shape == (3, 3)
        np.testing.assert_allclose(cov.enu_position, cov.enu_position.T, rtol=1e-9)
        assert result.to_dict()["covariance"]["position_radius95_m"] == cov.position_radius95_m
        scales.append(cov.position_radius95_m / cov.position_radius95)
    assert len(scales) == 4
    np.testing.assert_allclose(scales, scales[0], rtol=1e-9)
    assert abs(scales[0] / true_scale - 1) < 0.05  # the fit to 3 m GPS noise


def test_options(golden, golden_localizer):
    defaults = cwloc.default_options()
    assert defaults["nb"] == cwloc.Options().back_matches
    assert defaults["max_image_size"] == cwloc.Options().max_image_size
    options = cwloc.Options(nb=4, matcher="global-ratio", refine=False, seed=2**64 - 1)
    assert (options.back_matches, options.matcher, options.refine, options.seed) == \
        (4, "global-ratio", False, 2**64 - 1)
    options.set("max-error", 4.5)
    assert options.to_dict()["max_error"] == 4.5
    # options= is the base, keywords override it: the same as cwloc-localize's flags.
    _, queries = golden
    _, camera, features = queries[1]
    kp, desc = cwloc.read_feature_file(features)
    a = golden_localizer.localize_features(kp, desc, camera, options=cwloc.Options(nb=50), seed=3)
    b = golden_localizer.localize_features(kp, desc, camera, nb=50, seed=3)
    assert a.rotation.tolist() == b.rotation.tolist()
    assert a.to_dict()["parameters"] == b.to_dict()["parameters"]


def test_photo_gives_the_clis_pose(herz, herz_localizer, tmp_path):
    data, index = herz
    photo = data / "query_images" / "0012.jpg"
    out = tmp_path / "cli.jsonl"
    run([tool("cwloc-localize"), "--index", str(index), "--image", str(photo), *HERZ_FLAGS,
         "-q", "-o", str(out)])
    (cli,) = read_jsonl(out)
    assert cli["success"]
    for source in (str(photo), Path(photo), photo.read_bytes(), bytearray(photo.read_bytes()),
                   memoryview(photo.read_bytes())):
        result = herz_localizer.localize_photo(source, **HERZ_OPTIONS)
        assert result.success, type(source)
        assert result.rotation.tolist() == cli["pose"]["qvec"], type(source)
        assert result.translation.tolist() == cli["pose"]["tvec"], type(source)
        assert result.camera.focal_estimated and result.camera.model == "SIMPLE_RADIAL"
        assert result.times.extraction > 0


def test_photo_with_hloc_camera_gives_the_clis_pose(herz, herz_localizer, tmp_path):
    data, index = herz
    name, camera = (data / "queries_with_intrinsics.txt").read_text().splitlines()[0].split(
        " ", 1)
    photo = data / "query_images" / name
    out = tmp_path / "cli.jsonl"
    run([tool("cwloc-localize"), "--index", str(index), "--image", str(photo), "--camera",
         camera, *HERZ_FLAGS, "-q", "-o", str(out)])
    (cli,) = read_jsonl(out)
    result = herz_localizer.localize_photo(os.fspath(photo), camera, **HERZ_OPTIONS)
    assert result.success and not result.camera.focal_estimated
    assert result.rotation.tolist() == cli["pose"]["qvec"]
    assert result.translation.tolist() == cli["pose"]["tvec"]
