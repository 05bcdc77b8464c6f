"""cwloc: the 6-DoF pose of a photo inside a COLMAP model (docs/python.md).

    import cwloc
    localizer = cwloc.Localizer.open("model.cwl")
    result = localizer.localize_photo("photo.jpg", max_image_size=1600)
    if result.success:
        print(result.rotation, result.translation)  # COLMAP's cam_from_world, w x y z

Bindings of libcwloc.so's C++ API (cwloc/cwloc.hpp); every localize_* releases the GIL.
"""
from ._cwloc import (
    BadInputError,
    Camera,
    Error,
    ErrorCode,
    GeoPose,
    IndexInfo,
    Inliers,
    InternalError,
    InvalidArgumentError,
    Localizer,
    Options,
    OutOfMemoryError,
    PoseCovariance,
    PositionPrior,
    RankedImage,
    Result,
    RigImageResult,
    RigResult,
    StageTimes,
    Tracker,
    Tracking,
    apply_index_delta,
    default_options,
    read_feature_file,
    version,
)

__version__ = version()

__all__ = [
    "BadInputError", "Camera", "Error", "ErrorCode", "GeoPose", "IndexInfo", "Inliers",
    "InternalError", "InvalidArgumentError", "Localizer", "Options", "OutOfMemoryError",
    "PoseCovariance", "PositionPrior", "RankedImage", "Result", "RigImageResult", "RigResult",
    "StageTimes", "Tracker",
    "Tracking", "apply_index_delta", "default_options", "read_feature_file", "version",
    "__version__",
]

try:  # builds with the indexer (not a device build, -DCWLOC_WITH_COLMAP_DB=OFF)
    from ._cwloc import build_index
    __all__.append("build_index")
except ImportError:
    pass
