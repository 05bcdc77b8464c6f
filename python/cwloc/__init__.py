"""cwloc: the 6-DoF pose of a photo inside a COLMAP model (docs/python.md).

    import cwloc
    localizer = cwloc.Localizer.open("model.cwl")
    result = localizer.localize_photo("photo.jpg", max_image_size=1600)
    if result.success:
        print(result.rotation, result.translation)  # COLMAP's cam_from_world, w x y z
        print(result.covariance.position_radius95, result.camera.params)

Bindings of libcwloc.so's C++ API (cwloc/cwloc.hpp); every localize_* releases the GIL.
"""
from . import _cwloc
from ._cwloc import *  # noqa: F401,F403 (every class and function but the private ones)

__version__ = version()  # noqa: F405

# The extension's public names: its functions, errors, inputs, and the result classes made from
# the result types' descriptions (results/, docs/python.md); build_index in builds with the
# indexer.
__all__ = [name for name in dir(_cwloc) if not name.startswith("_")] + ["__version__"]
