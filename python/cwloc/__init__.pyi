# Type stubs of the cwloc package (the extension cwloc._cwloc); docs/python.md.
import os
from typing import Any, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, os.PathLike[str]]
_CameraLike = Union["Camera", "CameraUsed", "ResultCamera", str]
_Calibration = Literal["known", "focal-prior", "unknown", "focal_prior"]

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
    model: str  # COLMAP's camera model
    width: int  # px
    height: int  # px
    params: list[float]  # COLMAP's order for the model
    calibration: Literal['known', 'focal-prior', 'unknown']  # What the pose stage trusted: every parameter, a focal guess it refined, or only the image size
    def __init__(self, model: str, width: int, height: int, params: Sequence[float] = ...,
                 calibration: _Calibration = "known") -> None: ...
    @staticmethod
    def from_string(text: str, calibration: _Calibration = "known") -> Camera: ...
    @staticmethod
    def unknown(width: int, height: int) -> Camera: ...

class PositionPrior:
    latitude_deg: float  # deg
    longitude_deg: float  # deg
    height_m: Optional[float]  # Above the WGS84 ellipsoid; none: the radius is horizontal; m
    radius_m: float  # m
    source: Literal['option', 'priors-file', 'exif']  # --prior-position (or the API's), a --priors file, or the photo's EXIF GPS
    def __init__(self, latitude_deg: float, longitude_deg: float, radius_m: float,
                 height_m: Optional[float] = None) -> None: ...

class Options:
    position_prior: Optional[PositionPrior]
    gravity: Optional[npt.NDArray[np.float64]]
    def __init__(self, **options: Any) -> None: ...
    def set(self, name: str, value: Any) -> None: ...
    def to_dict(self) -> dict[str, Any]: ...
    def __getattr__(self, field: str) -> Any: ...  # one attribute per option-table field

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

# The classes below are the result types' descriptions (results/): their attribute lines are
# written by tools/stubs/update_stubs.py, which tests/python/test_stubs.py runs; methods by hand.

# One query's answer. success False is no error: failure_reason says why. The pose is COLMAP's cam_from_world: X_cam = R X_world + t
class Result:
    name: str  # The query's name
    success: bool
    failure_reason: str  # Why not localized
    rotation: npt.NDArray[np.float64]  # cam_from_world's unit quaternion (w, x, y, z), on success
    translation: npt.NDArray[np.float64]  # cam_from_world's translation, on success
    center: npt.NDArray[np.float64]  # The camera centre, model frame, on success; model units
    camera: ResultCamera
    focal_depth: Optional[FocalDepth]  # A localized query whose focal length was estimated and refined
    covariance: Optional[PoseCovariance]  # On success, unless the refinement problem is singular
    geo: Optional[GeoPose]  # On success with a georeferenced index
    priors: PriorsUsed
    num_inliers: int  # RANSAC inliers
    inlier_ratio: float  # Inliers per 2D-3D correspondence given to RANSAC
    num_features: int  # The query's
    features_searched: int  # In the kd-forest (fewer when a latency budget cut it)
    forward_matches: int  # 2D-3D matches of the forward search that passed the ratio tests
    back_matches: int  # 2D-3D matches of back-matching
    correspondences: int  # Unique 2D-3D pairs given to RANSAC
    back_matched_clusters: int  # Clusters back-matched (one model image each unless the index was built with --clusters)
    back_stop: Literal['target', 'images', 'no-votes', 'deadline', 'not-run', 'pinned', 'bound']  # Why back-matching stopped
    guided: bool  # Whether a pose hypothesis guided back-matching
    ransac_iterations: int  # RANSAC hypotheses drawn
    ranked_images: list[RankedImage]  # By votes
    photo: Optional[PhotoInfo]  # A photo query's
    tracking: Optional[Tracking]  # A frame of a sequence
    times: StageTimes
    budget: Optional[Budget]  # With a latency budget
    inliers: Inliers  # On success, in feature order
    @property
    def cam_from_world(self) -> npt.NDArray[np.float64]: ...  # rotation as a 3 x 3 matrix
    @property
    def json(self) -> str: ...  # the JSON record cwloc-localize writes
    def to_dict(self) -> dict[str, Any]: ...  # the JSON record

# The camera a query was localized with: estimated (SIMPLE_RADIAL) unless it was known
class ResultCamera:
    model: str  # COLMAP's camera model
    width: int  # px
    height: int  # px
    params: list[float]  # COLMAP's order for the model
    focal_estimated: bool  # Whether the focal length was estimated
    calibration: Literal['known', 'focal-prior', 'unknown']  # What the pose stage trusted: every parameter, a focal guess it refined, or only the image size
    intrinsics_source: Literal['camera-option', 'query-list', 'image-size-option', 'focal-option', 'exif', 'database', 'none']  # Where the camera came from: --camera, a query-list line, --image-size, --focal, the photo's EXIF, the COLMAP database, or nothing but its size
    distortion: Optional[Distortion]  # A localized query's lens distortion: the model it was fitted with, and why
    def to_dict(self) -> dict[str, Any]: ...

# How a localized query's lens distortion was fitted (docs/algorithm.md, section 4)
class Distortion:
    model: str  # The camera model of params (SIMPLE_RADIAL when the focal length was estimated)
    fit: Literal['given', 'estimated', 'held-at-zero']  # given: a known camera's, held fixed; estimated: SIMPLE_RADIAL's k refined with the focal length; held-at-zero: the focal length estimated without the final refinement, k = 0
    k: Optional[float]  # SIMPLE_RADIAL's radial distortion (fit estimated or held-at-zero)
    k_std: Optional[float]  # k's standard deviation from the final refinement's covariance
    k_significant: Optional[bool]  # |k| >= 2 k_std: the data constrain k
    why: str  # Why this fit
    def to_dict(self) -> dict[str, Any]: ...

# An estimated and refined focal length: how well it is told apart from the camera's distance to the scene, from the final refinement's covariance
class FocalDepth:
    correlation: float  # Between the focal length and the camera centre's position along its optical axis
    focal_std_px: float  # Standard deviation of the focal length; px
    depth_std: float  # Standard deviation of the camera centre along its optical axis; model units
    weakly_constrained: bool  # focal_std_px above 0.5 % of the focal length and |correlation| >= 0.95: the camera's distance is uncertain by about as much
    def to_dict(self) -> dict[str, Any]: ...

# How well the refined pose is known (docs/algorithm.md, 'Pose uncertainty'): from the final refinement's Jacobian and its inliers' residuals, widened by the index's calibration; an estimated focal length and distortion are marginalised out
class PoseCovariance:
    pose: npt.NDArray[np.float64]  # 6 x 6 over (theta, C): theta the rotation vector (radians, model frame) of the orientation's error, C the centre (model units)
    position_radius95: float  # The radius of the smallest sphere around the centre that holds its 95 % ellipsoid; model units
    focal_std_px: Optional[float]  # When the focal length was estimated: its standard deviation; px
    calibration: Optional[CovarianceScales]  # What the index's calibration multiplied the covariance by; none when the index has no calibration for the query's calibration mode
    enu_position: Optional[npt.NDArray[np.float64]]  # Georeferenced index: the centre's 3 x 3 covariance in the local east-north-up frame at the camera; m^2
    position_radius95_m: Optional[float]  # Georeferenced index: position_radius95 in metres; m
    def to_dict(self) -> dict[str, Any]: ...

# What the index's calibration multiplied a pose covariance's blocks by
class CovarianceScales:
    rotation: float  # The rotation block's
    position: float  # The centre block's
    def to_dict(self) -> dict[str, Any]: ...

# A localized camera on the globe, when the index is georeferenced (docs/geo.md)
class GeoPose:
    latitude_deg: float  # WGS84; deg
    longitude_deg: float  # WGS84, east; deg
    height_m: float  # Above the WGS84 ellipsoid; m
    enu: npt.NDArray[np.float64]  # East, north, up of the index's origin; m
    heading_deg: float  # The optical axis' heading, clockwise from true north, [0, 360); deg
    pitch_deg: float  # The optical axis above the horizon, [-90, 90]; deg
    roll_deg: float  # About the optical axis, (-180, 180]; deg
    def to_dict(self) -> dict[str, Any]: ...

# The query's priors as given (--prior-position, --prior-gravity, --priors, --use-exif-gps) and what they did
class PriorsUsed:
    position: Optional[PositionPriorUse]
    gravity: Optional[GravityPriorUse]
    def to_dict(self) -> dict[str, Any]: ...

# The position prior a query used, and what it did
class PositionPriorUse:
    latitude_deg: float  # deg
    longitude_deg: float  # deg
    height_m: Optional[float]  # Above the WGS84 ellipsoid; none: the radius is horizontal; m
    radius_m: float  # m
    source: Literal['option', 'priors-file', 'exif']  # --prior-position (or the API's), a --priors file, or the photo's EXIF GPS
    clusters_in_radius: int  # Clusters with a model camera within the radius: the only ones matched
    def to_dict(self) -> dict[str, Any]: ...

# The gravity prior a query used
class GravityPriorUse:
    direction: npt.NDArray[np.float64]  # The direction gravity pulls in the camera frame (x right, y down, z forward)
    error_deg: Optional[float]  # Angle between the prior and the localized pose's gravity; deg
    def to_dict(self) -> dict[str, Any]: ...

# A model image and the co-visibility votes it got
class RankedImage:
    image_id: int  # COLMAP's image id
    name: str  # Its name in the model
    votes: int
    def to_dict(self) -> dict[str, Any]: ...

# A photo query: the size of the image SIFT ran on (COLMAP's --max-image-size rule; keypoints are in the photo's own pixels) and the SIFT settings that made its features
class PhotoInfo:
    extraction_width: int  # px
    extraction_height: int  # px
    first_octave: int  # SIFT's first octave: -1 is COLMAP's, 0 and 1 the fast mode
    max_features: int  # SIFT's cap
    def to_dict(self) -> dict[str, Any]: ...

# How a frame of a sequence got its pose: tracked (matched near the pose predicted from the frames before it), relocalized (from scratch: the first frame, or tracking failed its checks) or lost (no pose)
class Tracking:
    mode: Literal['tracked', 'relocalized', 'lost']
    predicted_from: Optional[str]  # The frame whose pose the prediction started from; none for the first frame and after a reset
    prediction_error: Optional[float]  # Between the frame's camera centre and the predicted one; when both exist; model units
    prediction_error_deg: Optional[float]  # Rotation between the frame's pose and the predicted one; deg
    seconds: float  # The tracker's time on the frame after its features, relocalization included; s
    def to_dict(self) -> dict[str, Any]: ...

# Wall-clock time per pipeline stage
class StageTimes:
    extraction: float  # A photo's decoding and SIFT extraction; 0 for given features; s
    forward_knn: float  # kd-forest searches of the query's features; s
    ratio_test: float  # Cluster-wise ratio tests; s
    query_tree: float  # Building the kd-forest over the query's features; s
    back_matching: float  # Prioritized back-matching and co-visibility votes; s
    pose: float  # LO-RANSAC with the minimal solvers, then the final refinement; s
    total: float  # The whole query; s
    def to_dict(self) -> dict[str, Any]: ...

# A latency budget (--budget-ms) and the stages it cut short, in pipeline order
class Budget:
    ms: float  # ms
    cut: list[str]  # Of 'forward', 'back_matching', 'ransac', 'refinement'
    def to_dict(self) -> dict[str, Any]: ...

# A RANSAC inlier of the reported pose
class Inlier:
    feature: int  # Row of the query's features
    keypoint: npt.NDArray[np.float32]  # px
    point: int  # Row of the index's 3D points
    xyz: npt.NDArray[np.float64]  # The 3D point; model units
    view: int  # Row of the index's views: the one whose descriptor matched
    def to_dict(self) -> dict[str, Any]: ...

# Rows of Inlier, one array per field
class Inliers:
    feature: npt.NDArray[np.uint32]  # Row of the query's features
    keypoint: npt.NDArray[np.float32]  # px
    point: npt.NDArray[np.uint32]  # Row of the index's 3D points
    xyz: npt.NDArray[np.float64]  # The 3D point; model units
    view: npt.NDArray[np.uint32]  # Row of the index's views: the one whose descriptor matched
    def __len__(self) -> int: ...

# A rig frame's answer: the frame's pose (its reference camera's), the rig's, and every image's cam_from_world = cam_from_rig * rig_from_world
class RigResult:
    name: str  # The frame's id: a --frames FRAME_ID, or the image name after a rig camera's image_prefix
    success: bool
    failure_reason: str
    pose: Optional[Pose]  # The frame's pose: its reference camera's cam_from_world
    rig: RigPose
    covariance: Optional[PoseCovariance]  # The rig pose's, over (theta, C) of the rig
    geo: Optional[GeoPose]  # The reference camera on the globe (georeferenced index)
    images: list[RigImageResult]  # Per image, the reference first
    times: RigStageTimes
    @property
    def json(self) -> str: ...  # the JSON record cwloc-localize writes
    def to_dict(self) -> dict[str, Any]: ...  # the JSON record

# COLMAP's world-to-camera pose: X_cam = R(rotation) X_world + translation; center = -R^T translation
class Pose:
    rotation: npt.NDArray[np.float64]  # Unit quaternion (w, x, y, z)
    translation: npt.NDArray[np.float64]
    center: npt.NDArray[np.float64]  # The origin in the model frame; model units
    def to_dict(self) -> dict[str, Any]: ...

# A rig's pose and how it was found
class RigPose:
    reference_image: str  # The frame's first image, whose pose is the frame's
    rig_from_world: Optional[Pose]  # X_rig = R X_world + t; center the rig's origin; on success
    unknown_scale: bool  # The cam_from_rig translations were known up to one scale, estimated here (--frames-scale unknown)
    scale: float  # Model units per unit of the cam_from_rig translations (1 when known)
    scale_std: Optional[float]
    num_inliers: int  # RANSAC inliers over all images
    correspondences: int  # The images' 2D-3D pairs pooled for the rig's RANSAC
    ransac_iterations: int
    refined: bool  # The final refinement of the rig pose was kept
    mean_reprojection_error_px: Optional[float]  # Over the inliers, on success; px
    def to_dict(self) -> dict[str, Any]: ...

# One image of a rig frame's answer
class RigImageResult:
    name: str
    cam_from_rig: Transform  # Where the camera sits on the rig: X_cam = R X_rig + t
    pose: Optional[Pose]  # Its cam_from_world from the rig's pose (what --poses writes for it)
    camera: CameraUsed  # As the rig used it: a focal prior's SIMPLE_RADIAL refined with the rig pose
    num_inliers: int  # The rig's inliers in this image
    num_features: int
    forward_matches: int
    back_matches: int
    correspondences: int
    inliers: Inliers
    def to_dict(self) -> dict[str, Any]: ...

# A rigid transform as COLMAP names them: X_to = R(rotation) X_from + translation
class Transform:
    rotation: npt.NDArray[np.float64]  # Unit quaternion (w, x, y, z)
    translation: npt.NDArray[np.float64]
    def to_dict(self) -> dict[str, Any]: ...

# A camera as a localization used it
class CameraUsed:
    model: str  # COLMAP's camera model
    width: int  # px
    height: int  # px
    params: list[float]  # COLMAP's order for the model
    calibration: Literal['known', 'focal-prior', 'unknown']  # What the pose stage trusted: every parameter, a focal guess it refined, or only the image size
    intrinsics_source: Literal['camera-option', 'query-list', 'image-size-option', 'focal-option', 'exif', 'database', 'none']  # Where the camera came from: --camera, a query-list line, --image-size, --focal, the photo's EXIF, the COLMAP database, or nothing but its size
    def to_dict(self) -> dict[str, Any]: ...

# Wall-clock time of a rig frame's stages
class RigStageTimes:
    images: float  # The images' own pipelines, photo extraction excluded; s
    rig_pose: float  # The rig's RANSAC, refinement and covariance; s
    total: float  # The whole frame, photo extraction included; s
    def to_dict(self) -> dict[str, Any]: ...
