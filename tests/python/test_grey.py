"""localize_grey: an 8-bit frame with rows of any stride, the same pose as the photo."""
import io

import numpy as np
import pytest

import cwloc


def test_grey_image_gives_the_photos_pose(herz, herz_localizer):
    """As tests/api/localizer_api_tools_test.cc: a photo and its decoded grey pixels give one
    pose. A grey PNG decodes losslessly, so its pixels are exactly the array's."""
    image = pytest.importorskip("PIL.Image")
    data, _ = herz
    grey = np.asarray(image.open(data / "query_images" / "0017.jpg").convert("L"))
    png = io.BytesIO()
    image.fromarray(grey).save(png, format="PNG")
    options = {"max_image_size": 1600, "max_features": 6000}
    from_photo = herz_localizer.localize_photo(png.getvalue(), **options)
    assert from_photo.success and from_photo.camera.focal_estimated
    height, width = grey.shape
    camera = cwloc.Camera.unknown(width, height)
    padded = np.zeros((height, width + 16), np.uint8)
    padded[:, :width] = grey
    doubled = np.repeat(grey, 2, axis=1)
    for pixels in (grey, padded[:, :width], doubled[:, ::2]):  # contiguous, padded rows, copied
        result = herz_localizer.localize_grey(pixels, camera, **options)
        assert result.rotation.tolist() == from_photo.rotation.tolist()
        assert result.translation.tolist() == from_photo.translation.tolist()
        assert result.camera.params == from_photo.camera.params
