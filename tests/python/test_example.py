"""python/examples/localize_hloc_list.py writes the pose lines cwloc-localize --poses writes."""
import subprocess
import sys

from conftest import HERZ_FLAGS, SOURCE, read_jsonl, run, tool


def test_hloc_list(herz, tmp_path):
    data, index = herz
    lines = (data / "queries_with_intrinsics.txt").read_text().splitlines()[:3]
    queries = tmp_path / "queries.txt"
    queries.write_text(lines[0] + "\n" + lines[1] + "\n" + lines[2].split()[0] + "\n")
    images = data / "query_images"
    run([tool("cwloc-localize"), "--index", str(index), "--image-list", str(queries),
         "--image-dir", str(images), *HERZ_FLAGS, "-q", "-o", str(tmp_path / "cli.jsonl"),
         "--poses", str(tmp_path / "cli_poses.txt")])
    done = subprocess.run(
        [sys.executable, str(SOURCE / "python" / "examples" / "localize_hloc_list.py"),
         "--index", str(index), "--queries", str(queries), "--images", str(images),
         "--poses", str(tmp_path / "poses.txt"), "--jsonl", str(tmp_path / "results.jsonl"),
         "--threads", "2", "-O", "max_image_size=1600", "-O", "max_features=6000"],
        capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "3 of 3 queries localized" in done.stderr
    poses = (tmp_path / "poses.txt").read_text()
    assert poses == (tmp_path / "cli_poses.txt").read_text()
    assert [l.split()[0] for l in poses.splitlines()] == [l.split()[0] for l in lines]
    records = read_jsonl(tmp_path / "results.jsonl")
    cli = read_jsonl(tmp_path / "cli.jsonl")
    assert [r["pose"]["qvec"] for r in records] == [r["pose"]["qvec"] for r in cli]

