"""One Localizer on 4 threads: the same answers as one after the other (the GIL is released
while a query runs, so the threads really overlap)."""
from concurrent.futures import ThreadPoolExecutor

import cwloc
from conftest import HERZ_OPTIONS


def answer(result):
    return (result.success, result.rotation.tolist(), result.translation.tolist(),
            result.num_inliers, result.inliers.point.tolist())


def test_features_on_four_threads(golden, golden_localizer):
    _, queries = golden
    inputs = [(*cwloc.read_feature_file(f), camera) for _, camera, f in queries] * 4
    serial = [answer(golden_localizer.localize_features(*q)) for q in inputs]
    with ThreadPoolExecutor(max_workers=4) as pool:
        parallel = list(pool.map(lambda q: answer(golden_localizer.localize_features(*q)), inputs))
    assert parallel == serial
    assert all(a[0] for a in serial)


def test_photos_on_four_threads(herz, herz_localizer):
    data, _ = herz
    photos = [data / "query_images" / n for n in ("0002.jpg", "0012.jpg", "0022.jpg")] * 2
    serial = [answer(herz_localizer.localize_photo(p, **HERZ_OPTIONS)) for p in photos]
    with ThreadPoolExecutor(max_workers=4) as pool:
        parallel = list(pool.map(
            lambda p: answer(herz_localizer.localize_photo(p.read_bytes(), **HERZ_OPTIONS)),
            photos))
    assert parallel == serial
