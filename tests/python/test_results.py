"""The result classes are the result types' descriptions (results/describe.h): the stubs are
what the descriptions make, and every described field's attribute holds what the JSON record
writes at its key, on real results of every kind (a localized query with priors, a budget and a
georeferenced index, an unknown camera, a failed query, a tracker's frames, a rig frame and a
photo)."""
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import cwloc
from conftest import GOLDEN, SOURCE, run, shared_data, tool

CLASSES = {name: fields for name, _, fields in cwloc._cwloc._described_classes()}


def test_the_stubs_are_the_descriptions():
    done = subprocess.run([sys.executable, str(SOURCE / "tools" / "stubs" / "update_stubs.py"),
                           "--check"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_stub_check_names_a_stale_attribute(tmp_path):
    stubs = (SOURCE / "python" / "cwloc" / "__init__.pyi").read_text()
    stale = tmp_path / "stale.pyi"
    stale.write_text(stubs.replace("    votes: int\n", "    votes: float\n"))
    done = subprocess.run([sys.executable, str(SOURCE / "tools" / "stubs" / "update_stubs.py"),
                           "--check", str(stale)], capture_output=True, text=True)
    assert done.returncode == 1
    assert "-    votes: float" in done.stdout and "+    votes: int" in done.stdout


def at(record, key):
    """The record's value at a dotted key ("matches.forward"), or None."""
    for part in key.split("."):
        if not isinstance(record, dict) or part not in record:
            return None
        record = record[part]
    return record


def check(value, record, seen, where):
    """Every described field of `value` against the record `value` was written to."""
    name = type(value).__name__
    for field, _, _, key, scale, conditional in CLASSES[name]:
        attribute = getattr(value, field)
        if attribute is not None:
            seen.add((name, field))
        if hasattr(attribute, "__len__") and type(attribute).__name__ in CLASSES and len(attribute):
            # Columns of a list the record leaves out: each column was met.
            seen.update((type(attribute).__name__, column) for column, *_ in
                        CLASSES[type(attribute).__name__])
        expected = at(record, key) if key else None
        # Left out of the record (its description says why), or written only under a condition
        # (a pose on success) that does not hold.
        if not key or (conditional and expected is None):
            continue
        path = f"{where}.{field}"
        if attribute is None:
            assert expected is None, path
        elif type(attribute).__name__ in CLASSES:
            if expected is not None:  # an object of absent fields is left out (priors)
                check(attribute, expected, seen, path)
        elif isinstance(attribute, list) and attribute and type(attribute[0]).__name__ in CLASSES:
            assert len(attribute) == len(expected), path
            for i, (item, item_record) in enumerate(zip(attribute, expected)):
                check(item, item_record, seen, f"{path}[{i}]")
        elif isinstance(attribute, np.ndarray):
            assert attribute.tolist() == expected, path
        elif isinstance(attribute, float):
            assert attribute * scale == expected, path
        else:
            assert attribute == expected, path


def quaternion_product(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def cam_from_rig(reference, image):
    """An image's cam_from_rig from two lines of queries_gt.txt (NAME QW QX QY QZ TX TY TZ ...),
    the rig being the reference's camera: cam_from_world * reference_from_world^-1."""
    q0, t0 = [float(v) for v in reference[1:5]], np.array([float(v) for v in reference[5:8]])
    q, t = [float(v) for v in image[1:5]], np.array([float(v) for v in image[5:8]])
    rotation = quaternion_product(q, (q0[0], -q0[1], -q0[2], -q0[3]))
    w, x, y, z = rotation
    matrix = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                       [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                       [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return tuple(rotation), tuple((t - matrix @ t0).tolist())


@pytest.fixture(scope="module")
def results():
    """Results of every kind, each with the JSON record it was made with."""
    geo_folder = GOLDEN / "index-1.1-queries"
    geo = cwloc.Localizer.open(GOLDEN / "index-1.1.cwl")
    lines = [line.split() for line in (geo_folder / "queries_gt.txt").read_text().splitlines()
             if line.strip() and not line.startswith("#")]
    truth = {fields[0]: fields for fields in lines}
    geo_truth = {line.split()[0]: line.split()
                 for line in (geo_folder / "queries_geo.txt").read_text().splitlines()
                 if line.strip() and not line.startswith("#")}
    name = lines[0][0]
    features = cwloc.read_feature_file(geo_folder / (name + ".txt"))
    camera = " ".join(truth[name][8:])
    lat, lon, height = (float(v) for v in geo_truth[name][1:4])
    out = [geo.localize_features(*features, camera, prior_position=(lat, lon, 50.0, height),
                                 prior_gravity=(0.0, 1.0, 0.06), budget_ms=1e9),
           geo.localize_features(*features, cwloc.Camera.unknown(1024, 768)),
           geo.localize_features(*features, camera, min_inliers=100000)]
    tracker = cwloc.Tracker(geo)
    for fields in lines:
        out.append(tracker.track_features(
            *cwloc.read_feature_file(geo_folder / (fields[0] + ".txt")), " ".join(fields[8:])))
    images = []
    for fields in lines[:2]:
        keypoints, descriptors = cwloc.read_feature_file(geo_folder / (fields[0] + ".txt"))
        images.append({"name": fields[0], "keypoints": keypoints, "descriptors": descriptors,
                       "camera": " ".join(fields[8:]),
                       "cam_from_rig": cam_from_rig(lines[0], fields)})
    out.append(geo.localize_rig(images, unknown_scale=True, name="frame"))
    herz = shared_data("herz_jesu_p25")
    if herz is not None:  # a photo, and an index with the default covariance calibration
        with tempfile.TemporaryDirectory() as scratch:
            index = f"{scratch}/herz.cwl"
            run([tool("cwloc-index"), "build", "--model", str(herz / "mapping_model" / "bin"),
                 "--database", str(herz / "database.db"), "-o", index])
            photo = sorted((herz / "query_images").iterdir())[0]
            out.append(cwloc.Localizer.open(index).localize_photo(photo, max_image_size=800))
    return out


def test_every_field_holds_what_the_record_writes(results):
    seen = set()
    for i, result in enumerate(results):
        assert type(result).__name__ in ("Result", "RigResult")
        check(result, result.to_dict(), seen, f"results[{i}]")
    # Every field was met with a value somewhere, but those no such result has.
    never = {(name, field) for name, fields in CLASSES.items() for field, *_ in fields
             if name not in ("Camera", "PositionPrior")} - seen
    expected_never = set()
    if shared_data("herz_jesu_p25") is None:
        expected_never |= {("Result", "photo"), ("PhotoInfo", "extraction_width"),
                           ("PhotoInfo", "extraction_height"), ("PhotoInfo", "first_octave"),
                           ("PhotoInfo", "max_features"), ("PoseCovariance", "calibration"),
                           ("CovarianceScales", "rotation"), ("CovarianceScales", "position")}
    assert never == expected_never
