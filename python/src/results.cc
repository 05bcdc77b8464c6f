// Results as typed objects: the fields of api::Result, its arrays as numpy arrays (copies).
#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

// The inliers of the pose, one row each.
struct Inliers {
  py::array_t<uint32_t> features;  // N
  py::array_t<float> keypoints;    // N x 2
  py::array_t<uint32_t> points;    // N
  py::array_t<double> xyz;         // N x 3
};

Inliers ToInliers(const std::vector<api::Inlier>& inliers) {
  const auto n = static_cast<py::ssize_t>(inliers.size());
  Inliers out{py::array_t<uint32_t>(n), py::array_t<float>({n, py::ssize_t{2}}),
              py::array_t<uint32_t>(n), py::array_t<double>({n, py::ssize_t{3}})};
  for (py::ssize_t i = 0; i < n; ++i) {
    const api::Inlier& inlier = inliers[i];
    out.features.mutable_at(i) = inlier.feature;
    out.points.mutable_at(i) = inlier.point;
    for (int j = 0; j < 2; ++j) out.keypoints.mutable_at(i, j) = inlier.keypoint[j];
    for (int j = 0; j < 3; ++j) out.xyz.mutable_at(i, j) = inlier.xyz[j];
  }
  return out;
}

// R of a unit quaternion (w, x, y, z), as Eigen's toRotationMatrix computes it.
py::array_t<double> RotationMatrix(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  return Array(r, {3, 3});
}

template <typename T>
py::object OrNone(const std::optional<T>& value) {
  return value ? py::cast(*value) : py::none();
}

py::object Vector3OrNone(const std::optional<std::array<double, 3>>& value) {
  return value ? py::object(Array(value->data(), {3})) : py::none();
}

void BindParts(py::module_& m) {
  py::class_<Inliers>(m, "Inliers", "The RANSAC inliers of the reported pose, one row each.")
      .def_readonly("features", &Inliers::features, "uint32 (N,): rows of the query's features")
      .def_readonly("keypoints", &Inliers::keypoints, "float32 (N, 2): their pixels")
      .def_readonly("points", &Inliers::points, "uint32 (N,): rows of the index's 3D points")
      .def_readonly("xyz", &Inliers::xyz, "float64 (N, 3): the points, model frame")
      .def("__len__", [](const Inliers& i) { return i.features.size(); });

  py::class_<api::RankedImage>(m, "RankedImage", "A model image and its votes.")
      .def_readonly("image_id", &api::RankedImage::image_id, "COLMAP's image id")
      .def_readonly("name", &api::RankedImage::name, "Its name in the model")
      .def_readonly("votes", &api::RankedImage::votes, "Its votes")
      .def("__repr__", [](const api::RankedImage& r) {
        return "cwloc.RankedImage(" + std::to_string(r.image_id) + ", '" + r.name + "', " +
               std::to_string(r.votes) + ")";
      });

  py::class_<api::StageTimes> times(m, "StageTimes", "Wall-clock seconds per stage.");
#define CWLOC_STAGE_TIME(name, help) times.def_readonly(#name, &api::StageTimes::name, help);
#include "cwloc/stage_times.inc"
#undef CWLOC_STAGE_TIME
  times.def(
      "to_dict",
      [](const api::StageTimes& t) {
        py::dict out;
#define CWLOC_STAGE_TIME(name, help) out[#name] = t.name;
#include "cwloc/stage_times.inc"
#undef CWLOC_STAGE_TIME
        return out;
      },
      "{stage: seconds}");

  py::class_<api::GeoPose>(m, "GeoPose", "A localized camera on the globe (docs/geo.md).")
      .def_readonly("latitude_deg", &api::GeoPose::latitude_deg, "WGS84 latitude")
      .def_readonly("longitude_deg", &api::GeoPose::longitude_deg, "WGS84 longitude")
      .def_readonly("height_m", &api::GeoPose::height_m, "Above the ellipsoid")
      .def_property_readonly(
          "enu", [](const api::GeoPose& g) { return Array(g.enu.data(), {3}); },
          "float64 (3,): metres east, north, up of the index's origin")
      .def_readonly("heading_deg", &api::GeoPose::heading_deg, "Clockwise from north")
      .def_readonly("pitch_deg", &api::GeoPose::pitch_deg, "Above the horizon")
      .def_readonly("roll_deg", &api::GeoPose::roll_deg, "About the optical axis");

  py::class_<api::CovarianceScales>(
      m, "CovarianceScales",
      "What the index's calibration multiplied a pose covariance's blocks by.")
      .def_readonly("rotation", &api::CovarianceScales::rotation, "The rotation block's factor")
      .def_readonly("position", &api::CovarianceScales::position, "The centre block's factor");

  py::class_<api::PoseCovariance>(m, "PoseCovariance",
                                  "How well the refined pose is known (docs/algorithm.md).")
      .def_property_readonly(
          "pose",
          [](const api::PoseCovariance& c) {
            return Array(c.pose.data(), {6, 6});
          },
          "float64 (6, 6) over (rotation vector, camera centre), model units")
      .def_property_readonly(
          "position",
          [](const api::PoseCovariance& c) {
            double block[9];
            for (int i = 0; i < 3; ++i)
              for (int j = 0; j < 3; ++j) block[3 * i + j] = c.pose[6 * (3 + i) + 3 + j];
            return Array(block, {3, 3});
          },
          "float64 (3, 3): the camera centre's block of pose")
      .def_readonly("position_radius95", &api::PoseCovariance::position_radius95,
                    "Model units: the centre's 95 % ellipsoid lies within it")
      .def_property_readonly(
          "focal_std_px", [](const api::PoseCovariance& c) { return OrNone(c.focal_std_px); },
          "Standard deviation of an estimated focal length, or None")
      .def_property_readonly(
          "calibration", [](const api::PoseCovariance& c) { return OrNone(c.calibration); },
          "CovarianceScales the index's calibration widened pose by, or None")
      .def_property_readonly(
          "enu_position",
          [](const api::PoseCovariance& c) -> py::object {
            return c.enu_position ? py::object(Array(c.enu_position->data(), {3, 3})) : py::none();
          },
          "float64 (3, 3) in square metres east-north-up (georeferenced index), or None")
      .def_property_readonly(
          "position_radius95_m",
          [](const api::PoseCovariance& c) { return OrNone(c.position_radius95_m); },
          "The 95 % radius in metres (georeferenced index), or None");

  py::class_<api::Tracking>(m, "Tracking", "How a Tracker's frame got its pose.")
      .def_property_readonly(
          "mode",
          [](const api::Tracking& t) {
            return std::string(kTrackingModeNames[static_cast<size_t>(t.mode)]);
          },
          "'tracked' (matched near the predicted pose), 'relocalized' (from scratch) or 'lost' "
          "(no pose)")
      .def_property_readonly(
          "predicted_from",
          [](const api::Tracking& t) {
            return t.predicted_from.empty() ? py::none() : py::cast(t.predicted_from);
          },
          "The frame the prediction started from, or None")
      .def_property_readonly(
          "prediction_error", [](const api::Tracking& t) { return OrNone(t.prediction_error); },
          "Model units between the pose's centre and the prediction's, or None")
      .def_property_readonly(
          "prediction_error_deg",
          [](const api::Tracking& t) { return OrNone(t.prediction_error_deg); },
          "Degrees between the pose and the prediction, or None")
      .def_readonly("seconds", &api::Tracking::seconds, "The tracker's whole time on the frame");
  py::class_<api::IndexInfo>(m, "IndexInfo", "An opened index.")
      .def_readonly("path", &api::IndexInfo::path, "The file")
      .def_readonly("format_version", &api::IndexInfo::format_version, "'MAJOR.MINOR'")
      .def_readonly("num_images", &api::IndexInfo::num_images, "Model images")
      .def_readonly("num_points", &api::IndexInfo::num_points, "3D points")
      .def_readonly("num_views", &api::IndexInfo::num_views, "Observations, one descriptor each")
      .def_readonly("georeferenced", &api::IndexInfo::georeferenced,
                    "Whether results have a GeoPose and queries may have priors")
      .def_readonly("origin_latitude_deg", &api::IndexInfo::origin_latitude_deg, "ENU origin")
      .def_readonly("origin_longitude_deg", &api::IndexInfo::origin_longitude_deg, "ENU origin")
      .def_readonly("origin_height_m", &api::IndexInfo::origin_height_m, "ENU origin")
      .def("__repr__", [](const api::IndexInfo& i) {
        return "cwloc.IndexInfo('" + i.path + "', format " + i.format_version + ", " +
               std::to_string(i.num_images) + " images, " + std::to_string(i.num_points) +
               " points, " + std::to_string(i.num_views) + " views)";
      });
}

}  // namespace

void BindResults(py::module_& m) {
  BindParts(m);
  using R = api::Result;
  py::class_<R> result(m, "Result",
                       "One query's answer. success False is no error: failure_reason says why. "
                       "The pose is COLMAP's cam_from_world: X_cam = R X_world + t.");
  // The result's numbers (num_inliers, the match counts, ...): result_fields.inc.
#define CWLOC_RESULT_FIELD(name, type, group, key, help) result.def_readonly(#name, &R::name, help);
#include "cwloc/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  result.def_readonly("success", &R::success, "Whether the query was localized")
      .def_readonly("failure_reason", &R::failure_reason, "Why not, when success is False")
      .def_property_readonly(
          "rotation", [](const R& r) { return Array(r.rotation.data(), {4}); },
          "float64 (4,): cam_from_world's quaternion w, x, y, z")
      .def_property_readonly(
          "translation", [](const R& r) { return Array(r.translation.data(), {3}); },
          "float64 (3,): cam_from_world's translation")
      .def_property_readonly(
          "cam_from_world", [](const R& r) { return RotationMatrix(r.rotation); },
          "float64 (3, 3): the rotation matrix of rotation")
      .def_property_readonly(
          "center", [](const R& r) { return Array(r.center.data(), {3}); },
          "float64 (3,): the camera centre, model frame")
      .def_readonly("camera", &R::camera, "The camera used; estimated unless it was known")
      .def_readonly("focal_estimated", &R::focal_estimated, "Whether the focal was estimated")
      .def_property_readonly(
          "inliers", [](const R& r) { return ToInliers(r.inliers); }, "Inliers (arrays)")
      .def_readonly("ranked_images", &R::ranked_images, "[RankedImage] by votes")
      .def_readonly("times", &R::times, "StageTimes, seconds")
      .def_property_readonly(
          "geo", [](const R& r) { return OrNone(r.geo); },
          "GeoPose on a georeferenced index, else None")
      .def_property_readonly(
          "position_prior", [](const R& r) { return OrNone(r.position_prior); },
          "The PositionPrior used (option or EXIF GPS), or None")
      .def_readonly("clusters_in_radius", &R::clusters_in_radius,
                    "Clusters with a model camera within the position prior")
      .def_property_readonly(
          "gravity", [](const R& r) { return Vector3OrNone(r.gravity); },
          "float64 (3,): the gravity prior used, or None")
      .def_property_readonly(
          "gravity_error_deg", [](const R& r) { return OrNone(r.gravity_error_deg); },
          "Degrees between the gravity prior and the pose's gravity, or None")
      .def_property_readonly(
          "covariance", [](const R& r) { return OrNone(r.covariance); },
          "PoseCovariance on success, else None")
      .def_property_readonly(
          "tracking", [](const R& r) { return OrNone(r.tracking); },
          "Tracking for a Tracker's frame, else None")
      .def_readonly("json", &R::json, "The JSON record cwloc-localize writes for this query")
      .def(
          "to_dict", [](const R& r) { return py::module_::import("json").attr("loads")(r.json); },
          "json.loads(json)")
      .def("__repr__", [](const R& r) {
        return r.success ? "cwloc.Result(success, " + std::to_string(r.num_inliers) + " inliers)"
                         : "cwloc.Result(failed: " + r.failure_reason + ")";
      });
}

}  // namespace cwloc::python
