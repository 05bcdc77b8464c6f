// cwloc.Tracker: a stream's frames in order (api::Tracker), inputs converted with the GIL held
// and the frame run without it; a lock keeps one frame at a time per tracker.
#include <array>
#include <mutex>
#include <utility>

#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

struct Tracker {
  Tracker(const api::Localizer& localizer, const api::Options& frame_options)
      : tracker(localizer, frame_options), options(frame_options) {}
  api::Tracker tracker;
  const api::Options options;  // the frames' records echo them
  std::mutex frame;            // one frame at a time, whatever the Python threads do
};

// motion: None, or ((w, x, y, z), (tx, ty, tz)[, (sigma_rotation_deg, sigma_position)]), the
// frame's camera from the previous one's and its standard deviations.
std::optional<api::Motion> ToMotion(py::handle motion) {
  if (motion.is_none()) return std::nullopt;
  try {
    if (!py::isinstance<py::sequence>(motion)) throw py::cast_error();
    const auto parts = motion.cast<py::sequence>();
    if (parts.size() != 2 && parts.size() != 3) throw py::cast_error();
    api::Motion out{parts[0].cast<std::array<double, 4>>(), parts[1].cast<std::array<double, 3>>()};
    if (parts.size() == 3) {
      const auto sigmas = parts[2].cast<std::array<double, 2>>();
      out.sigma_rotation_deg = sigmas[0];
      out.sigma_position = sigmas[1];
    }
    return out;
  } catch (const py::cast_error&) {
    throw py::type_error(
        "motion: expected ((w, x, y, z), (tx, ty, tz)[, (sigma_rotation_deg, sigma_position)]) "
        "or None");
  }
}

std::unique_ptr<Tracker> Create(const api::Localizer& localizer, const py::kwargs& kwargs) {
  return std::make_unique<Tracker>(localizer, ToOptions(kwargs));
}

// timestamp: None, or the frame's time in seconds.
std::optional<double> ToTimestamp(py::handle timestamp) {
  if (timestamp.is_none()) return std::nullopt;
  try {
    return timestamp.cast<double>();
  } catch (const py::cast_error&) {
    throw py::type_error("timestamp: expected a number of seconds or None");
  }
}

Record<api::Result> TrackPhoto(Tracker& tracker, py::handle photo, py::handle camera,
                               py::handle timestamp_in, py::handle motion_in) {
  const std::string path = ToPath(photo, "photo");
  std::optional<api::Camera> frame_camera;
  if (!camera.is_none()) frame_camera = ToCamera(camera, "camera");
  const std::optional<double> timestamp = ToTimestamp(timestamp_in);
  const std::optional<api::Motion> motion = ToMotion(motion_in);
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return {tracker.tracker.TrackPhoto(path, frame_camera, timestamp, motion), tracker.options};
}

Record<api::Result> TrackFeatures(Tracker& tracker, py::handle keypoints, py::handle descriptors,
                                  py::handle camera, py::handle timestamp_in,
                                  py::handle motion_in) {
  const api::Features features = ToFeatures(keypoints, descriptors);
  const api::Camera frame_camera = ToCamera(camera, "camera");
  const std::optional<double> timestamp = ToTimestamp(timestamp_in);
  const std::optional<api::Motion> motion = ToMotion(motion_in);
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return {tracker.tracker.Track(features, frame_camera, timestamp, motion), tracker.options};
}

Record<api::Result> TrackGrey(Tracker& tracker, py::handle image, py::handle camera,
                              py::handle timestamp_in, py::handle motion_in) {
  const GreyImage grey = ToGreyImage(image);
  const api::Camera frame_camera = ToCamera(camera, "camera");
  const std::optional<double> timestamp = ToTimestamp(timestamp_in);
  const std::optional<api::Motion> motion = ToMotion(motion_in);
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return {tracker.tracker.TrackGreyImage(grey.pixels, grey.width, grey.height, grey.stride,
                                         frame_camera, timestamp, motion),
          tracker.options};
}

}  // namespace

void BindTracker(py::module_& m) {
  py::class_<Tracker>(m, "Tracker",
                      "The frames of one moving camera, in order (cwloc-localize --sequence): "
                      "each frame is tracked from the frames before it, localized from scratch "
                      "when that fails, or lost (no pose); every Result has tracking. Keyword "
                      "options as Localizer.localize_* take them, for every frame. Frames run "
                      "without the GIL, one at a time per tracker; trackers of one Localizer may "
                      "run on several threads.")
      .def(py::init(&Create), py::arg("localizer"), py::keep_alive<1, 2>())
      .def("track_photo", &TrackPhoto, py::arg("photo"), py::arg("camera") = py::none(),
           py::arg("timestamp") = py::none(), py::arg("motion") = py::none(),
           "The next frame as a JPEG or PNG file (a str or os.PathLike), as localize_photo. "
           "timestamp: when it was seen, seconds (with the two frames' before, the last step is "
           "scaled to the time since the last frame). motion: the camera's motion since the "
           "previous frame, ((w, x, y, z), (tx, ty, tz)) of the frame's camera from the previous "
           "one's, metres (cwloc-localize --motion).")
      .def("track_features", &TrackFeatures, py::arg("keypoints"), py::arg("descriptors"),
           py::arg("camera"), py::arg("timestamp") = py::none(), py::arg("motion") = py::none(),
           "The next frame's SIFT features, as localize_features; timestamp and motion as "
           "track_photo.")
      .def("track_grey", &TrackGrey, py::arg("image"), py::arg("camera"),
           py::arg("timestamp") = py::none(), py::arg("motion") = py::none(),
           "The next frame as an 8-bit grey image, as localize_grey; timestamp and motion as "
           "track_photo.")
      .def(
          "reset",
          [](Tracker& tracker) {
            const std::lock_guard lock(tracker.frame);
            tracker.tracker.Reset();
          },
          "Forgets the frames so far: the next frame is localized from scratch.");
}

}  // namespace cwloc::python
