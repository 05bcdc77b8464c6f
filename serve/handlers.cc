// The request handlers of cwloc-serve's API (docs/serve.md, "Endpoints").
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <span>

#include "app/query_priors.h"
#include "app/result_json.h"
#include "base/error.h"
#include "camera/camera_models.h"
#include "geo/index_georeference.h"
#include "localizer/geo_priors.h"
#include "serve/geopose_protocol.h"
#include "serve/query_body.h"
#include "serve/server_impl.h"

namespace cwloc {
namespace {

using Clock = WorkQueue::Clock;

// The photo or features of a request: a multipart part 'image' or 'features', or the body.
struct RequestBody {
  std::string_view bytes;
  std::string content_type;
  std::string what;      // how errors name it
  std::string filename;  // a part's
};

RequestBody BodyOf(const httplib::Request& req) {
  if (req.is_multipart_form_data()) {
    for (const char* part : {"image", "features"}) {
      if (req.has_file(part)) {
        const auto& file = req.files.find(part)->second;
        return {file.content, file.content_type, std::string("part '") + part + "'", file.filename};
      }
    }
    throw HttpError{400, "multipart request without an 'image' or a 'features' part",
                    "bad_request"};
  }
  if (req.body.empty()) {
    throw HttpError{400,
                    "empty body: send a JPEG or PNG, features, or multipart/form-data with an "
                    "'image' part",
                    "bad_request"};
  }
  return {req.body, req.get_header_value("Content-Type"), "body", ""};
}

std::string OptionsPart(const httplib::Request& req) {
  if (!req.is_multipart_form_data() || !req.has_file("options")) return "";
  return req.files.find("options")->second.content;
}

void SetJson(httplib::Response& res, const nlohmann::ordered_json& json) {
  res.set_content(json.dump(), "application/json");
}

double ParamNumber(const httplib::Request& req, const char* name, std::optional<double> fallback) {
  if (!req.has_param(name)) {
    if (fallback) return *fallback;
    throw HttpError{400, std::string("give ?") + name + "=", "bad_request"};
  }
  const std::string text = req.get_param_value(name);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value))
    throw HttpError{400, std::string("?") + name + "=" + text + ": expected a number",
                    "bad_request"};
  return value;
}

}  // namespace

std::shared_ptr<const ServedIndex> Server::Impl::IndexOf(const httplib::Request& req) const {
  const std::string name = req.get_param_value("index");
  std::shared_ptr<const ServedIndex> served = registry.Find(name);
  if (!served)
    throw HttpError{404, "no index named '" + name + "' (GET /v1/info lists them)", "not_found"};
  return served;
}

RequestInputs Server::Impl::InputsOf(const std::string& options_json) const {
  RequestInputs inputs;
  inputs.options = options.defaults;
  if (!options_json.empty()) ApplyRequestOptions(options_json, limits, &inputs);
  inputs.options.photo.sift.num_threads = 1;
  return inputs;
}

Clock::time_point Server::Impl::DeadlineFrom(Clock::time_point start) const {
  const double budget_ms = options.defaults.localizer.budget_ms;
  if (budget_ms <= 0) return start + std::chrono::hours(24 * 365);
  return start + std::chrono::microseconds(static_cast<int64_t>(budget_ms * 1e3));
}

void Server::Impl::BoundByDeadline(Clock::time_point deadline, QueryOptions* query) const {
  if (options.defaults.localizer.budget_ms <= 0) return;
  const double left_ms =
      std::max(1e-3, std::chrono::duration<double, std::milli>(deadline - Clock::now()).count());
  double& budget = query->localizer.budget_ms;
  budget = budget > 0 ? std::min(budget, left_ms) : left_ms;
}

double ServiceTimes::Expected(bool photo) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seconds_[photo];
}

void ServiceTimes::Add(bool photo, double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  double& average = seconds_[photo];
  average = average == 0 ? seconds : 0.9 * average + 0.1 * seconds;
}

void Server::Impl::RunOnWorker(const std::function<void()>& job, bool photo,
                               Clock::time_point deadline) {
  std::exception_ptr error;
  const std::function<void()> caught = [&] {
    const Clock::time_point start = Clock::now();
    try {
      job();
    } catch (...) {
      error = std::current_exception();
    }
    service_times.Add(photo, std::chrono::duration<double>(Clock::now() - start).count());
  };
  const Clock::time_point start_by =
      deadline -
      std::chrono::microseconds(static_cast<int64_t>(service_times.Expected(photo) * 1e6));
  switch (work.Run(caught, start_by)) {
    case WorkQueue::Outcome::kDone:
      break;
    case WorkQueue::Outcome::kQueueFull:
      throw HttpError{503, BusyMessage(work.capacity()), "overloaded"};
    case WorkQueue::Outcome::kExpired:
      throw HttpError{503,
                      "busy: no worker was free early enough to answer within --budget-ms; retry "
                      "later",
                      "expired"};
    case WorkQueue::Outcome::kStopped:
      throw HttpError{503, "the server is stopping", "stopping"};
  }
  if (error) std::rethrow_exception(error);
}

void Server::Impl::Localize(const httplib::Request& req, httplib::Response& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  RequestInputs inputs = InputsOf(OptionsPart(req));
  const RequestBody body = BodyOf(req);
  if (!body.filename.empty() && inputs.name == "query") inputs.name = body.filename;
  const BodyKind kind = BodyKindOf(body.content_type, body.bytes);
  nlohmann::ordered_json record;
  RunOnWorker(
      [&] {
        const Query query = QueryFromBody(body.bytes, kind, inputs, body.what);
        BoundByDeadline(deadline, &inputs.options);
        const LocalizationResult result =
            served->localizer.Localize(query, inputs.options.localizer);
        metrics.CountResult(result.success, result.times);
        record = ResultToJson(result, inputs.options);
      },
      kind == BodyKind::kPhoto, deadline);
  SetJson(res, record);
}

void Server::Impl::GeoPose(const httplib::Request& req, httplib::Response& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  RequestInputs inputs = InputsOf("");
  const GeoPoseRequest request = ParseGeoPoseRequest(req.body, &inputs);
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  if (!served->localizer.geo()) {
    throw HttpError{
        400, "index '" + served->spec.name + "' is not georeferenced (cwloc-index build --georef)",
        "bad_request"};
  }
  inputs.name = request.id.empty() ? "geopose" : request.id;
  std::optional<LocalizationResult> result;
  RunOnWorker(
      [&] {
        const Query query =
            request.grey ? QueryFromGreyPixels(request.image, request.width, request.height, inputs,
                                               "geopose image")
                         : QueryFromBody(request.image, BodyKind::kPhoto, inputs, "geopose image");
        BoundByDeadline(deadline, &inputs.options);
        result = served->localizer.Localize(query, inputs.options.localizer);
        metrics.CountResult(result->success, result->times);
      },
      /*photo=*/true, deadline);
  if (!result->success) {
    throw HttpError{422, "not localized: " + result->failure_reason, "not_localized"};
  }
  SetJson(res, GeoPoseResponse(request.id, *result, served->localizer.geo()->frame()));
}

void Server::Impl::StartSession(const httplib::Request& req, httplib::Response& res) {
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  auto session = std::make_shared<Session>(served, InputsOf(req.body));
  const std::string id = sessions.Add(session);
  if (id.empty()) {
    throw HttpError{503, "too many open sessions (--max-sessions); end one or retry later",
                    "sessions_full"};
  }
  res.status = 201;
  nlohmann::ordered_json answer;
  answer["session"] = id;
  answer["index"] = served->spec.name;
  answer["expires_after_s"] = std::chrono::duration<double>(sessions.time_to_live()).count();
  SetJson(res, answer);
}

void Server::Impl::SessionFrame(const httplib::Request& req, httplib::Response& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  const std::string id = req.matches[1];
  const std::shared_ptr<Session> session = sessions.Find(id);
  if (!session) {
    throw HttpError{404, "no session '" + id + "' (ended, or unused for --session-ttl)",
                    "not_found"};
  }
  RequestInputs inputs = session->inputs;
  inputs.timestamp.reset();
  inputs.motion.reset();
  if (const std::string part = OptionsPart(req); !part.empty()) {
    ApplyRequestOptions(part, limits, &inputs);
    inputs.options.photo.sift.num_threads = 1;
    if (OptionsToJson(inputs.options) != OptionsToJson(session->inputs.options)) {
      throw InputError(
          "options: a frame cannot change the session's pipeline options; give them when the "
          "session starts (a frame may give name, timestamp, motion, camera, image_size, focal, "
          "unknown_focal and the priors)");
    }
  }
  const RequestBody body = BodyOf(req);
  if (!body.filename.empty() && inputs.name == session->inputs.name) inputs.name = body.filename;
  std::unique_lock<std::mutex> one_frame(session->busy, std::try_to_lock);
  if (!one_frame.owns_lock()) {
    throw HttpError{409, "session '" + id + "' is still tracking its previous frame",
                    "session_busy"};
  }
  const BodyKind kind = BodyKindOf(body.content_type, body.bytes);
  nlohmann::ordered_json record;
  RunOnWorker(
      [&] {
        const Query query = QueryFromBody(body.bytes, kind, inputs, body.what);
        const LocalizationResult result =
            session->tracker.Track(query, inputs.timestamp, inputs.motion);
        metrics.CountResult(result.success, result.times);
        record = ResultToJson(result, session->inputs.options);
      },
      kind == BodyKind::kPhoto, deadline);
  SetJson(res, record);
}

void Server::Impl::EndSession(const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1];
  if (!sessions.Remove(id)) throw HttpError{404, "no session '" + id + "'", "not_found"};
  res.status = 204;
}

void Server::Impl::Coverage(const httplib::Request& req, httplib::Response& res) {
  const double latitude = ParamNumber(req, "lat", std::nullopt);
  const double longitude = ParamNumber(req, "lon", std::nullopt);
  const double radius = ParamNumber(req, "radius", kDefaultExifGpsRadiusM);
  char text[96];
  std::snprintf(text, sizeof(text), "%.10f %.10f %.6f", latitude, longitude, radius);
  const PositionPrior region = ParsePositionPrior(text, "coverage");
  nlohmann::ordered_json answer;
  answer["available"] = false;
  answer["indexes"] = nlohmann::json::array();
  for (const auto& served : registry.All()) {
    if (!served->localizer.geo()) continue;
    const IndexGeo::CamerasNear near = served->localizer.geo()->CamerasWithin(region);
    answer["indexes"].push_back({{"name", served->spec.name},
                                 {"cameras_within", near.count},
                                 {"nearest_camera_m", near.nearest_m}});
    if (near.count > 0) answer["available"] = true;
  }
  SetJson(res, answer);
}

void Server::Impl::Info(const httplib::Request&, httplib::Response& res) {
  nlohmann::ordered_json answer;
  answer["indexes"] = nlohmann::json::array();
  for (const auto& served : registry.All()) answer["indexes"].push_back(served->Info());
  answer["default_index"] = answer["indexes"][0]["name"];
  answer["threads"] = work.threads();
  answer["queue"] = work.capacity();
  answer["max_body_bytes"] = options.max_body_bytes;
  answer["session_ttl_s"] = options.session_ttl_s;
  answer["parameters"] = OptionsToJson(options.defaults);
  SetJson(res, answer);
}

void Server::Impl::Map(const httplib::Request& req, httplib::Response& res) {
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  const Index& index = served->index;
  const double wanted = ParamNumber(req, "max_points", 50000);
  if (wanted < 0 || wanted > 5e6)
    throw HttpError{400, "?max_points=: expected 0 to 5000000", "bad_request"};
  const size_t max_points = static_cast<size_t>(wanted);
  const size_t stride =
      max_points == 0 ? 0 : std::max<size_t>(1, (index.num_points() + max_points - 1) / max_points);
  std::vector<float> points;
  std::vector<uint8_t> colors;  // when the index has them (cwloc-index build --point-colors)
  const std::span<const PointColor> point_colors = index.point_colors();
  for (size_t p = 0; stride > 0 && p < index.num_points(); p += stride) {
    const std::array<double, 3> xyz = index.PointXyz(static_cast<uint32_t>(p));
    points.insert(points.end(), {static_cast<float>(xyz[0]), static_cast<float>(xyz[1]),
                                 static_cast<float>(xyz[2])});
    if (!point_colors.empty())
      colors.insert(colors.end(), point_colors[p].rgb, point_colors[p].rgb + 3);
  }
  nlohmann::ordered_json answer;
  answer["index"] = served->spec.name;
  answer["num_points"] = index.num_points();
  answer["points"] = points;
  if (!point_colors.empty()) answer["colors"] = colors;
  answer["cameras"] = nlohmann::json::array();
  for (const IndexImage& image : index.images()) {
    const Eigen::Vector3d center = CameraCenterOf(image);
    const IndexCamera& camera = index.cameras()[image.camera_index];
    answer["cameras"].push_back(
        {{"name", index.ImageName(image)},
         {"rotation", std::span<const double>(image.cam_from_world_rotation, 4)},
         {"center", {center.x(), center.y(), center.z()}},
         {"camera",
          {{"model", CameraModelName(static_cast<CameraModelId>(camera.model_id))},
           {"width", camera.width},
           {"height", camera.height},
           {"params", std::span<const double>(camera.params, camera.num_params)}}}});
  }
  SetJson(res, answer);
}

}  // namespace cwloc
