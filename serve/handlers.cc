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
#include "serve/base64.h"
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

RequestBody BodyOf(const HttpRequest& req) {
  if (req.IsMultipart()) {
    for (const char* name : {"image", "features"}) {
      if (const FormPart* part = req.Part(name))
        return {part->content, part->content_type, std::string("part '") + name + "'",
                part->filename};
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
  return {req.body, req.Header("content-type"), "body", ""};
}

std::string OptionsPart(const HttpRequest& req) {
  const FormPart* part = req.IsMultipart() ? req.Part("options") : nullptr;
  return part != nullptr ? std::string(part->content) : "";
}

void SetJson(HttpResponse& res, const nlohmann::ordered_json& json) {
  res.SetContent(json.dump(), "application/json");
}

double ParamNumber(const HttpRequest& req, const char* name, std::optional<double> fallback) {
  if (req.params.count(name) == 0) {
    if (fallback) return *fallback;
    throw HttpError{400, std::string("give ?") + name + "=", "bad_request"};
  }
  const std::string text = req.Param(name);
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value))
    throw HttpError{400, std::string("?") + name + "=" + text + ": expected a number",
                    "bad_request"};
  return value;
}

}  // namespace

std::shared_ptr<const ServedIndex> Server::Impl::IndexOf(const HttpRequest& req) const {
  const std::string name = req.Param("index");
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

void Server::Impl::Defer(HttpResponse& res, std::function<void(HttpResponse&)> work, bool photo,
                         Clock::time_point deadline) {
  res.deferred = DeferredWork{std::move(work), photo, deadline};
}

void Server::Impl::RunDeferred(DeferredWork deferred, std::shared_ptr<HttpResponse> res,
                               std::function<void()> done) {
  // The work, its refusals as the response, its time for the next requests' deadlines.
  auto job = std::make_shared<DeferredWork>(std::move(deferred));
  const auto answer = [this, res](const HttpError& error) {
    if (!error.kind.empty()) metrics.CountError(error.kind);
    SetError(*res, error);
  };
  const auto run = [this, job, res, answer] {
    const Clock::time_point start = Clock::now();
    try {
      job->work(*res);
    } catch (const HttpError& e) {
      answer(e);
    } catch (const InputError& e) {
      answer({400, e.what(), "bad_request"});
    } catch (const std::bad_alloc&) {
      answer({503, "out of memory", "out_of_memory"});
    } catch (const std::exception& e) {
      answer({500, std::string("internal error: ") + e.what(), "internal"});
    }
    service_times.Add(job->photo, std::chrono::duration<double>(Clock::now() - start).count());
  };
  const Clock::time_point start_by =
      job->deadline -
      std::chrono::microseconds(static_cast<int64_t>(service_times.Expected(job->photo) * 1e6));
  work.Post(run, start_by, [this, answer, done](WorkQueue::Outcome outcome) {
    switch (outcome) {
      case WorkQueue::Outcome::kDone:
        break;
      case WorkQueue::Outcome::kQueueFull:
        answer({503, BusyMessage(work.capacity()), "overloaded"});
        break;
      case WorkQueue::Outcome::kExpired:
        answer({503,
                "busy: no worker was free early enough to answer within --budget-ms; retry later",
                "expired"});
        break;
      case WorkQueue::Outcome::kStopped:
        answer({503, "the server is stopping", "stopping"});
        break;
    }
    done();
  });
}

void Server::Impl::Localize(const HttpRequest& req, HttpResponse& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  RequestInputs inputs = InputsOf(OptionsPart(req));
  const RequestBody body = BodyOf(req);
  if (!body.filename.empty() && inputs.name == "query") inputs.name = body.filename;
  const BodyKind kind = BodyKindOf(body.content_type, body.bytes);
  // The request (and so the body's bytes) outlives the deferred work (http_server.h).
  Defer(
      res,
      [this, served, inputs, body, kind, deadline](HttpResponse& answer) mutable {
        const Query query = QueryFromBody(body.bytes, kind, inputs, body.what);
        BoundByDeadline(deadline, &inputs.options);
        const LocalizationResult result =
            served->localizer.Localize(query, inputs.options.localizer);
        metrics.CountResult(result.success, result.times);
        SetJson(answer, ResultToJson(result, inputs.options));
      },
      kind == BodyKind::kPhoto, deadline);
}

void Server::Impl::GeoPose(const HttpRequest& req, HttpResponse& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  RequestInputs inputs = InputsOf("");
  auto request = std::make_shared<const GeoPoseRequest>(ParseGeoPoseRequest(req.body, &inputs));
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  if (!served->localizer.geo()) {
    throw HttpError{
        400, "index '" + served->spec.name + "' is not georeferenced (cwloc-index build --georef)",
        "bad_request"};
  }
  inputs.name = request->id.empty() ? "geopose" : request->id;
  Defer(
      res,
      [this, served, inputs, request, deadline](HttpResponse& answer) mutable {
        const Query query =
            request->grey
                ? QueryFromGreyPixels(request->image, request->width, request->height, inputs,
                                      "geopose image")
                : QueryFromBody(request->image, BodyKind::kPhoto, inputs, "geopose image");
        BoundByDeadline(deadline, &inputs.options);
        const LocalizationResult result =
            served->localizer.Localize(query, inputs.options.localizer);
        metrics.CountResult(result.success, result.times);
        if (!result.success)
          throw HttpError{422, "not localized: " + result.failure_reason, "not_localized"};
        SetJson(answer, GeoPoseResponse(request->id, result, served->localizer.geo()->frame()));
      },
      /*photo=*/true, deadline);
}

// What opens a session again travels in its id (sessions.h), so it is kept small.
constexpr size_t kMaxSessionOptionsBytes = 2048;

void Server::Impl::StartSession(const HttpRequest& req, HttpResponse& res) {
  const std::shared_ptr<const ServedIndex> served = IndexOf(req);
  if (req.body.size() > kMaxSessionOptionsBytes) {
    throw InputError("session options: " + std::to_string(req.body.size()) + " bytes, over " +
                     std::to_string(kMaxSessionOptionsBytes) +
                     " (they travel in the session's id)");
  }
  auto session = std::make_shared<Session>(served, InputsOf(req.body));
  const std::string id =
      sessions.Add(session, EncodeBase64Url(served->spec.name + '\n' + req.body));
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

void Server::Impl::SessionFrame(const HttpRequest& req, HttpResponse& res) {
  const Clock::time_point deadline = DeadlineFrom(Clock::now());
  const std::string id = req.matches[1];
  const std::shared_ptr<Session> session = SessionOf(id, res);
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
  if (session->busy.exchange(true)) {
    throw HttpError{409, "session '" + id + "' is still tracking its previous frame",
                    "session_busy"};
  }
  // Frees the session for its next frame when the frame is answered or turned away.
  std::shared_ptr<void> one_frame(nullptr, [session](void*) { session->busy = false; });
  const BodyKind kind = BodyKindOf(body.content_type, body.bytes);
  Defer(
      res,
      [this, id, session, inputs, body, kind, one_frame](HttpResponse& answer) mutable {
        // Released as the frame's answer is made, before the client can send the next.
        const std::shared_ptr<void> frame = std::move(one_frame);
        const Query query = QueryFromBody(body.bytes, kind, inputs, body.what);
        const LocalizationResult result =
            session->tracker.Track(query, inputs.timestamp, inputs.motion);
        sessions.Touch(id);  // its time to live from this answer, not from the request
        metrics.CountResult(result.success, result.times);
        SetJson(answer, ResultToJson(result, session->inputs.options));
      },
      kind == BodyKind::kPhoto, deadline);
}

std::shared_ptr<Session> Server::Impl::SessionOf(const std::string& id, HttpResponse& res) {
  bool ended = false;
  if (std::shared_ptr<Session> session = sessions.Find(id, &ended)) return session;
  const HttpError none{404, "no session '" + id + "' (ended, or unused for --session-ttl)",
                       "not_found"};
  const size_t dot = id.find('.');
  if (ended || dot != 32) throw none;
  // Never held here: opened again from what its id carries.
  std::string opened_by;
  try {
    opened_by = DecodeBase64(std::string_view(id).substr(dot + 1), "session id");
  } catch (const InputError&) {
    throw none;
  }
  const size_t newline = opened_by.find('\n');
  if (newline == std::string::npos) throw none;
  const std::shared_ptr<const ServedIndex> served = registry.Find(opened_by.substr(0, newline));
  if (!served) throw none;
  auto session = std::make_shared<Session>(served, InputsOf(opened_by.substr(newline + 1)));
  if (!sessions.Reopen(id, session)) {
    throw HttpError{503, "too many open sessions (--max-sessions); end one or retry later",
                    "sessions_full"};
  }
  res.SetHeader("X-Cwloc-Session", "reopened");
  session = sessions.Find(id, &ended);  // the one that stayed, when two frames raced
  if (!session) throw none;
  return session;
}

void Server::Impl::EndSession(const HttpRequest& req, HttpResponse& res) {
  const std::string id = req.matches[1];
  if (!sessions.Remove(id)) throw HttpError{404, "no session '" + id + "'", "not_found"};
  res.status = 204;
}

void Server::Impl::Coverage(const HttpRequest& req, HttpResponse& res) {
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

void Server::Impl::Info(const HttpRequest&, HttpResponse& res) {
  nlohmann::ordered_json answer;
  answer["indexes"] = nlohmann::json::array();
  for (const auto& served : registry.All()) answer["indexes"].push_back(served->Info());
  answer["default_index"] = answer["indexes"][0]["name"];
  answer["threads"] = work.threads();
  answer["queue"] = work.capacity();
  answer["max_body_bytes"] = options.http.max_body_bytes;
  answer["session_ttl_s"] = options.session_ttl_s;
  answer["parameters"] = OptionsToJson(options.defaults);
  SetJson(res, answer);
}

void Server::Impl::Map(const HttpRequest& req, HttpResponse& res) {
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
