// cwloc.Tracker: a stream's frames in order (api::Tracker), inputs converted with the GIL held
// and the frame run without it; a lock keeps one frame at a time per tracker.
#include <mutex>

#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

struct Tracker {
  Tracker(const api::Localizer& localizer, const api::Options& options)
      : tracker(localizer, options) {}
  api::Tracker tracker;
  std::mutex frame;  // one frame at a time, whatever the Python threads do
};

std::unique_ptr<Tracker> Create(const api::Localizer& localizer, const py::kwargs& kwargs) {
  return std::make_unique<Tracker>(localizer, ToOptions(kwargs));
}

api::Result TrackPhoto(Tracker& tracker, py::handle photo, py::handle camera) {
  const std::string path = ToPath(photo, "photo");
  std::optional<api::Camera> frame_camera;
  if (!camera.is_none()) frame_camera = ToCamera(camera, "camera");
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return tracker.tracker.TrackPhoto(path, frame_camera);
}

api::Result TrackFeatures(Tracker& tracker, py::handle keypoints, py::handle descriptors,
                          py::handle camera) {
  const api::Features features = ToFeatures(keypoints, descriptors);
  const api::Camera frame_camera = ToCamera(camera, "camera");
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return tracker.tracker.Track(features, frame_camera);
}

api::Result TrackGrey(Tracker& tracker, py::handle image, py::handle camera) {
  const GreyImage grey = ToGreyImage(image);
  const api::Camera frame_camera = ToCamera(camera, "camera");
  py::gil_scoped_release release;
  const std::lock_guard lock(tracker.frame);
  return tracker.tracker.TrackGreyImage(grey.pixels, grey.width, grey.height, grey.stride,
                                        frame_camera);
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
           "The next frame as a JPEG or PNG file (a str or os.PathLike), as localize_photo.")
      .def("track_features", &TrackFeatures, py::arg("keypoints"), py::arg("descriptors"),
           py::arg("camera"), "The next frame's SIFT features, as localize_features.")
      .def("track_grey", &TrackGrey, py::arg("image"), py::arg("camera"),
           "The next frame as an 8-bit grey image, as localize_grey.")
      .def(
          "reset",
          [](Tracker& tracker) {
            const std::lock_guard lock(tracker.frame);
            tracker.tracker.Reset();
          },
          "Forgets the frames so far: the next frame is localized from scratch.");
}

}  // namespace cwloc::python
