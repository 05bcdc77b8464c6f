# Type stubs of the cwloc package (the extension cwloc._cwloc); docs/python.md.
import os
from typing import Any, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, os.PathLike[str]]
_CameraLike = Union["Camera", str]
_Calibration = Literal["known", "focal_prior", "unknown"]

def version() -> str: ...
def default_options() -> dict[str, Any]: ...
def read_feature_file(path: _Path) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.uint8]]: ...
def build_index(model: _Path, database: _Path, output: _Path, **options: Any) -> dict[str, Any]: ...
def apply_index_delta(index: _Path, delta: _Path, output: _Path, threads: int = 0) -> None: ...

class ErrorCode:  # a pybind11 enum: int(code) is the C API's cwloc_status
    INVALID_ARGUMENT: ErrorCode
    BAD_INPUT: ErrorCode
    OUT_OF_MEMORY: ErrorCode
    INTERNAL: ErrorCode
    @property
    def value(self) -> int: ...
    def __int__(self) -> int: ...

class Error(RuntimeError):
    code: ErrorCode

class InvalidArgumentError(Error, ValueError): ...
class BadInputError(Error): ...
class OutOfMemoryError(Error, MemoryError): ...
class InternalError(Error): ...

class Camera:
    model: str
    width: int
    height: int
    params: list[float]
    calibration: _Calibration
    def __init__(self, model: str, width: int, height: int, params: Sequence[float] = ...,
                 calibration: _Calibration = "known") -> None: ...
    @staticmethod
    def from_string(text: str, calibration: _Calibration = "known") -> Camera: ...
    @staticmethod
    def unknown(width: int, height: int) -> Camera: ...

class PositionPrior:
    latitude_deg: float
    longitude_deg: float
    height_m: Optional[float]
    radius_m: float
    def __init__(self, latitude_deg: float, longitude_deg: float, radius_m: float,
                 height_m: Optional[float] = None) -> None: ...

class Options:
    position_prior: Optional[PositionPrior]
    gravity: Optional[npt.NDArray[np.float64]]
    def __init__(self, **options: Any) -> None: ...
    def set(self, name: str, value: Any) -> None: ...
    def to_dict(self) -> dict[str, Any]: ...
    def __getattr__(self, field: str) -> Any: ...  # one attribute per option-table field

class Inliers:
    features: npt.NDArray[np.uint32]
    keypoints: npt.NDArray[np.float32]
    points: npt.NDArray[np.uint32]
    xyz: npt.NDArray[np.float64]
    def __len__(self) -> int: ...

class RankedImage:
    image_id: int
    name: str
    votes: int

class StageTimes:
    extraction: float
    forward_knn: float
    ratio_test: float
    query_tree: float
    back_matching: float
    pose: float
    total: float
    def to_dict(self) -> dict[str, float]: ...

class GeoPose:
    latitude_deg: float
    longitude_deg: float
    height_m: float
    enu: npt.NDArray[np.float64]
    heading_deg: float
    pitch_deg: float
    roll_deg: float

class CovarianceScales:
    rotation: float
    position: float

class PoseCovariance:
    pose: npt.NDArray[np.float64]
    position: npt.NDArray[np.float64]
    position_radius95: float
    focal_std_px: Optional[float]
    calibration: Optional[CovarianceScales]
    enu_position: Optional[npt.NDArray[np.float64]]
    position_radius95_m: Optional[float]

class IndexInfo:
    path: str
    format_version: str
    num_images: int
    num_points: int
    num_views: int
    georeferenced: bool
    origin_latitude_deg: float
    origin_longitude_deg: float
    origin_height_m: float

class Tracking:
    mode: str  # 'tracked', 'relocalized' or 'lost'
    predicted_from: Optional[str]
    prediction_error: Optional[float]
    prediction_error_deg: Optional[float]
    seconds: float

class Result:
    success: bool
    failure_reason: str
    rotation: npt.NDArray[np.float64]
    translation: npt.NDArray[np.float64]
    cam_from_world: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]
    camera: Camera
    focal_estimated: bool
    # The result's numbers, one per line of result_fields.inc (its help says what each counts).
    num_inliers: int
    inlier_ratio: float
    num_features: int
    features_searched: int
    forward_matches: int
    back_matches: int
    correspondences: int
    back_matched_clusters: int
    guided: bool
    ransac_iterations: int
    inliers: Inliers
    ranked_images: list[RankedImage]
    times: StageTimes
    geo: Optional[GeoPose]
    position_prior: Optional[PositionPrior]
    clusters_in_radius: int
    gravity: Optional[npt.NDArray[np.float64]]
    gravity_error_deg: Optional[float]
    covariance: Optional[PoseCovariance]
    tracking: Optional[Tracking]
    json: str
    def to_dict(self) -> dict[str, Any]: ...

class RigImageResult:
    name: str
    posed: bool
    rotation: npt.NDArray[np.float64]  # cam_from_world = cam_from_rig * rig_from_world
    translation: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]
    num_inliers: int
    camera: Camera

class RigResult:
    success: bool
    failure_reason: str
    rotation: npt.NDArray[np.float64]  # rig_from_world: X_rig = R X_world + t
    translation: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]
    scale: float
    scale_std: Optional[float]
    num_inliers: int
    correspondences: int
    covariance: Optional[PoseCovariance]
    geo: Optional[GeoPose]
    images: list[RigImageResult]
    json: str
    def to_dict(self) -> dict[str, Any]: ...

_Bytes = Union[bytes, bytearray, memoryview]
# A rig image: name, photo (a path) or keypoints and descriptors, camera, and cam_from_rig
# ((w, x, y, z), (tx, ty, tz)).
_RigImage = dict[str, Any]

class Localizer:
    def __init__(self, path: _Path, verify: bool = False) -> None: ...
    @staticmethod
    def open(path: _Path, verify: bool = False) -> Localizer: ...
    def info(self) -> IndexInfo: ...
    def localize_photo(self, photo: Union[_Path, _Bytes], camera: Optional[_CameraLike] = None,
                       **options: Any) -> Result: ...
    def localize_features(self, keypoints: npt.ArrayLike, descriptors: npt.ArrayLike,
                          camera: _CameraLike, **options: Any) -> Result: ...
    def localize_grey(self, image: npt.ArrayLike, camera: _CameraLike, **options: Any) -> Result: ...
    def localize_rig(self, images: list[_RigImage], unknown_scale: bool = False,
                     name: str = "frame", **options: Any) -> RigResult: ...

_Motion = Union[tuple[tuple[float, float, float, float], tuple[float, float, float]],
                tuple[tuple[float, float, float, float], tuple[float, float, float],
                      tuple[float, float]]]

class Tracker:
    def __init__(self, localizer: Localizer, **options: Any) -> None: ...
    def track_photo(self, photo: _Path, camera: Optional[_CameraLike] = None,
                    motion: Optional[_Motion] = None) -> Result: ...
    def track_features(self, keypoints: npt.ArrayLike, descriptors: npt.ArrayLike,
                       camera: _CameraLike, motion: Optional[_Motion] = None) -> Result: ...
    def track_grey(self, image: npt.ArrayLike, camera: _CameraLike,
                   motion: Optional[_Motion] = None) -> Result: ...
    def reset(self) -> None: ...
