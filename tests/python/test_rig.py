"""Localizer.localize_rig gives cwloc-localize --frames's poses bit for bit."""
import numpy as np

import cwloc
from conftest import read_jsonl, run, tool


def quaternion(r):
    """(w, x, y, z) of a rotation matrix, w >= 0 (for the test's frames file)."""
    w = np.sqrt(max(0.0, 1 + np.trace(r))) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    return np.array([w, x, y, z]) / np.linalg.norm([w, x, y, z])


def rotation(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def test_rig_frames_give_the_clis_poses(golden, golden_localizer, tmp_path):
    index, queries = golden
    truth = {}
    for line in (index.parent / "index-1.0-queries" / "queries_gt.txt").read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            f = line.split()
            truth[f[0]] = (rotation([float(v) for v in f[1:5]]), np.array([float(v) for v in f[5:8]]))
    chosen = [q for q in queries if q[0] in ("query_00002.jpg", "query_00003.jpg")]
    reference = truth[chosen[0][0]]
    images, lines = [], []
    for name, camera, features in chosen:
        r, t = truth[name]
        r_rig = r @ reference[0].T
        q, t_rig = quaternion(r_rig), t - r_rig @ reference[1]
        lines.append(f"w {features} {' '.join(repr(float(v)) for v in (*q, *t_rig))} {camera}")
        keypoints, descriptors = cwloc.read_feature_file(features)
        images.append({"name": str(features), "keypoints": keypoints, "descriptors": descriptors,
                       "camera": camera, "cam_from_rig": (q.tolist(), t_rig.tolist())})
    frames = tmp_path / "frames.txt"
    frames.write_text("\n".join(lines) + "\n")
    out = tmp_path / "rig.jsonl"
    run([tool("cwloc-localize"), "--index", str(index), "--frames", str(frames), "-q",
         "-o", str(out)])
    (cli,) = read_jsonl(out)
    result = golden_localizer.localize_rig(images, name="w")
    assert isinstance(result, cwloc.RigResult)
    assert cli["success"] and result.success
    assert result.rig.rig_from_world.rotation.tolist() == cli["rig"]["rig_from_world"]["qvec"]
    assert result.rig.rig_from_world.translation.tolist() == cli["rig"]["rig_from_world"]["tvec"]
    assert result.rig.num_inliers == cli["rig"]["num_inliers"]
    for image, record in zip(result.images, cli["images"]):
        assert image.pose is not None and image.name == record["name"]
        assert image.pose.rotation.tolist() == record["pose"]["qvec"]
        assert image.pose.translation.tolist() == record["pose"]["tvec"]
    assert result.to_dict()["rig"] == cli["rig"]


def test_a_rig_image_without_features_or_photo_is_refused(golden_localizer):
    try:
        golden_localizer.localize_rig([{"name": "a"}])
    except ValueError as error:
        assert str(error) == "images[0]: give 'photo', or 'keypoints' and 'descriptors'"
    else:
        raise AssertionError("no error")
