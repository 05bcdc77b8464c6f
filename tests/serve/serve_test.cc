// cwloc-serve against a running server on a free localhost port: its results are cwloc-localize's
// bit for bit (photos, features, sessions), its GeoPose answers agree with the result records,
// coverage and metrics count what they say (docs/serve.md).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>
#include <tuple>

#include "app/photo_query.h"
#include "app/query_priors.h"
#include "indexer/index_builder.h"
#include "tests/serve/serve_process.h"
#include "tests/shared_data_index.h"

namespace cwloc {
namespace {

using nlohmann::json;
using test::ServeProcess;

constexpr double kPi = 3.14159265358979323846;
const Geodetic kOrigin{50.7753, 6.0839, 180.0};

class ServeTest : public testing::Test {
 protected:
  void SetUp() override {
    shared_ = test::BuildSharedDataIndex("herz_jesu_p25");
    if (!shared_) GTEST_SKIP() << "no ../shared/data/herz_jesu_p25";
    data_ = shared_->data;
  }

  std::filesystem::path Photo(const std::string& name) const {
    return data_ / "query_images" / name;
  }

  // queries_with_intrinsics.txt's camera of a query: "MODEL W H PARAMS".
  std::string CameraOf(const std::string& name) const {
    std::ifstream in(data_ / "queries_with_intrinsics.txt");
    for (std::string line; std::getline(in, line);) {
      if (line.rfind(name + " ", 0) == 0) return line.substr(name.size() + 1);
    }
    ADD_FAILURE() << name << " is not in queries_with_intrinsics.txt";
    return "";
  }

  // A camera line's parts, as GeoPose requests give them: model, width, height, parameters.
  static std::tuple<std::string, int, int, std::vector<double>> CameraParts(
      const std::string& camera) {
    std::istringstream fields(camera);
    std::string model;
    int width = 0, height = 0;
    fields >> model >> width >> height;
    std::vector<double> params;
    for (double value; fields >> value;) params.push_back(value);
    return {model, width, height, params};
  }

  // cwloc-localize's JSON lines with these arguments.
  std::vector<json> LocalizeWithTheCli(const std::string& arguments) const {
    const auto out = dir_ / "cli.jsonl";
    std::string output;
    EXPECT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " " + arguments +
                                   " -q -o " + test::Quote(out),
                               &output),
              0)
        << output;
    std::vector<json> records;
    std::istringstream lines(test::ReadFile(out));
    for (std::string line; std::getline(lines, line);) records.push_back(json::parse(line));
    return records;
  }

  static json Posted(httplib::Client& client, const std::string& path,
                     const httplib::MultipartFormDataItems& items, int status = 200) {
    const auto response = client.Post(path, items);
    EXPECT_TRUE(response) << path;
    if (!response) return {};
    EXPECT_EQ(response->status, status) << response->body;
    return json::parse(response->body);
  }

  // herz_jesu_p25 placed on the globe at kOrigin (test::WriteStrechaGeorefFile), with its
  // points' colours, once per build.
  std::filesystem::path GeoreferencedIndex() const {
    const auto folder = test::SharedFixture("herz_georeferenced", [&](const auto& out) {
      const Index plain = Index::Open(shared_->index);
      test::WriteStrechaGeorefFile(data_, plain, kOrigin, out / "georef.txt");
      IndexBuildOptions options;
      options.model_dir = data_ / "mapping_model" / "bin";
      options.database_path = data_ / "database.db";
      options.output_path = out / "index.cwl";
      options.calibration_samples = 0;
      options.point_colors = true;
      options.georeferencing.georef_file = out / "georef.txt";
      BuildIndex(options);
    });
    return folder / "index.cwl";
  }

  std::optional<test::SharedDataIndex> shared_;
  std::filesystem::path data_;
  test::TempDir dir_;
};

TEST_F(ServeTest, APhotoGetsTheCliPoseBitForBit) {
  ServeProcess server({"--index", shared_->index.string(), "--threads", "2"});
  auto client = server.Client();
  const std::string photo = test::ReadFile(Photo("0002.jpg"));

  // The bare body, with the server's defaults.
  const auto bare = client.Post("/v1/localize", photo, "image/jpeg");
  ASSERT_TRUE(bare);
  ASSERT_EQ(bare->status, 200) << bare->body;
  EXPECT_EQ(bare->get_header_value("Content-Type"), "application/json");
  const json record = json::parse(bare->body);
  const json cli = LocalizeWithTheCli("--index " + test::Quote(shared_->index) + " --image " +
                                      test::Quote(Photo("0002.jpg")))
                       .at(0);
  ASSERT_TRUE(record["success"].get<bool>());
  EXPECT_EQ(record["pose"], cli["pose"]);
  EXPECT_EQ(record["camera"], cli["camera"]);
  EXPECT_EQ(record["num_inliers"], cli["num_inliers"]);
  EXPECT_EQ(record["parameters"], cli["parameters"]);
  EXPECT_GT(record["num_inliers"].get<int>(), 500);
  // curl --data-binary @photo.jpg without a Content-Type sends it as a form: read as bytes.
  const auto as_form = client.Post("/v1/localize", photo, "application/x-www-form-urlencoded");
  ASSERT_TRUE(as_form);
  ASSERT_EQ(as_form->status, 200) << as_form->body;
  EXPECT_EQ(json::parse(as_form->body)["pose"], cli["pose"]);

  // Multipart with options and a known camera: the CLI with the same flags.
  const std::string camera = CameraOf("0002.jpg");
  const json with_options =
      Posted(client, "/v1/localize",
             {{"image", photo, "0002.jpg", "image/jpeg"},
              {"options", R"({"max-features": 2000, "nb": 5, "camera": ")" + camera + R"("})", "",
               "application/json"}});
  const json cli_options =
      LocalizeWithTheCli("--index " + test::Quote(shared_->index) + " --image " +
                         test::Quote(Photo("0002.jpg")) + " --max-features 2000 --nb 5 --camera '" +
                         camera + "'")
          .at(0);
  EXPECT_EQ(with_options["name"], "0002.jpg");  // the part's file name
  EXPECT_EQ(with_options["pose"], cli_options["pose"]);
  EXPECT_EQ(with_options["parameters"], cli_options["parameters"]);
  EXPECT_EQ(with_options["parameters"]["max_features"], 2000);
  EXPECT_EQ(with_options["camera"]["intrinsics_source"], "camera-option");

  const auto file = dir_ / "record.json";
  std::ofstream(file) << with_options.dump();
  std::string report;
  EXPECT_EQ(test::ValidateJson("localization-result.schema.json", file, false, &report), 0)
      << report;
}

TEST_F(ServeTest, FeaturesAsTextOrBinaryGetTheCliPoseBitForBit) {
  PhotoOptions small;  // features as a device extracts them, at a smaller size
  small.max_image_size = 1024;
  const Query extracted = LoadPhotoQuery(Photo("0007.jpg"), "0007.jpg", small);
  // COLMAP's text features, as cwloc-localize --features reads them.
  std::string text = std::to_string(extracted.NumFeatures()) + " 128\n";
  for (uint32_t i = 0; i < extracted.NumFeatures(); ++i) {
    char line[64];
    std::snprintf(line, sizeof(line), "%.9g %.9g 1 0", extracted.keypoints[2 * i],
                  extracted.keypoints[2 * i + 1]);
    text += line;
    for (int d = 0; d < 128; ++d) text += " " + std::to_string(extracted.Descriptor(i)[d]);
    text += "\n";
  }
  const std::string binary = test::BinaryFeatureBody(extracted);
  const auto feature_file = dir_ / "0007.txt";
  std::ofstream(feature_file) << text;

  const std::string camera = CameraOf("0007.jpg");
  const json cli = LocalizeWithTheCli("--index " + test::Quote(shared_->index) + " --features " +
                                      test::Quote(feature_file) + " --camera '" + camera + "'")
                       .at(0);
  ServeProcess server({"--index", shared_->index.string()});
  auto client = server.Client();
  const std::string options = R"({"camera": ")" + camera + R"("})";
  const json from_text = Posted(
      client, "/v1/localize",
      {{"features", text, "0007.txt", "text/plain"}, {"options", options, "", "application/json"}});
  const json from_binary = Posted(client, "/v1/localize",
                                  {{"features", binary, "0007.bin", "application/octet-stream"},
                                   {"options", options, "", "application/json"}});
  ASSERT_TRUE(cli["success"].get<bool>());
  EXPECT_EQ(from_text["pose"], cli["pose"]);
  EXPECT_EQ(from_binary["pose"], cli["pose"]);
  EXPECT_EQ(from_binary["num_inliers"], cli["num_inliers"]);
}

TEST_F(ServeTest, ASessionTracksFramesAsTheCliSequenceDoes) {
  const std::vector<std::string> frames = {"0002.jpg", "0007.jpg", "0012.jpg"};
  std::string images;
  for (const std::string& frame : frames) images += " --image " + test::Quote(Photo(frame));
  const std::vector<json> cli = LocalizeWithTheCli("--index " + test::Quote(shared_->index) +
                                                   " --sequence --max-image-size 800" + images);
  ASSERT_EQ(cli.size(), frames.size());

  ServeProcess server({"--index", shared_->index.string(), "--session-ttl", "60"});
  auto client = server.Client();
  const auto started =
      client.Post("/v1/sessions", R"({"max-image-size": 800})", "application/json");
  ASSERT_TRUE(started);
  ASSERT_EQ(started->status, 201) << started->body;
  const std::string id = json::parse(started->body)["session"];
  EXPECT_EQ(id.find('.'), 32u);  // 32 random hex digits, then what opened it
  for (size_t i = 0; i < frames.size(); ++i) {
    const json record =
        Posted(client, "/v1/sessions/" + id + "/frames",
               {{"image", test::ReadFile(Photo(frames[i])), frames[i], "image/jpeg"}});
    EXPECT_EQ(record["name"], frames[i]);
    EXPECT_EQ(record["pose"], cli[i]["pose"]) << frames[i];
    EXPECT_EQ(record["tracking"]["mode"], cli[i]["tracking"]["mode"]) << frames[i];
  }
  // A frame cannot change the session's pipeline.
  const json refused =
      Posted(client, "/v1/sessions/" + id + "/frames",
             {{"image", test::ReadFile(Photo("0002.jpg")), "0002.jpg", "image/jpeg"},
              {"options", R"({"nb": 3})", "", "application/json"}},
             400);
  EXPECT_EQ(refused["error"],
            "options: a frame cannot change the session's pipeline options; give them when the "
            "session starts (a frame may give name, timestamp, motion, camera, image_size, "
            "focal, unknown_focal and the priors)");
  const auto ended = client.Delete("/v1/sessions/" + id);
  ASSERT_TRUE(ended);
  EXPECT_EQ(ended->status, 204);
  const json gone =
      Posted(client, "/v1/sessions/" + id + "/frames",
             {{"image", test::ReadFile(Photo("0002.jpg")), "0002.jpg", "image/jpeg"}}, 404);
  EXPECT_EQ(gone["error"], "no session '" + id + "' (ended, or unused for --session-ttl)");
}

// A replica that restarts (or takes over from one that died) opens a session again from its
// id: the next frame gets 200, localized from scratch as a new session's first frame is, and
// the frames after it go as in that new session. A session that ended or expired on its
// server stays ended.
TEST_F(ServeTest, ASessionGoesOnOnAServerThatNeverHeldItAndEndsWhereItEnded) {
  const std::vector<json> fresh = LocalizeWithTheCli(
      "--index " + test::Quote(shared_->index) + " --sequence --max-image-size 800 --image " +
      test::Quote(Photo("0012.jpg")) + " --image " + test::Quote(Photo("0017.jpg")));
  ASSERT_EQ(fresh.size(), 2u);
  const auto frame = [&](httplib::Client& client, const std::string& id, const std::string& name,
                         int status = 200) {
    return Posted(client, "/v1/sessions/" + id + "/frames",
                  {{"image", test::ReadFile(Photo(name)), name, "image/jpeg"}}, status);
  };
  std::string id;
  {
    ServeProcess first({"--index", shared_->index.string()});
    auto client = first.Client();
    const auto started =
        client.Post("/v1/sessions", R"({"max-image-size": 800})", "application/json");
    ASSERT_TRUE(started);
    ASSERT_EQ(started->status, 201) << started->body;
    id = json::parse(started->body)["session"];
    EXPECT_TRUE(frame(client, id, "0002.jpg")["success"].get<bool>());
    EXPECT_TRUE(frame(client, id, "0007.jpg")["success"].get<bool>());
  }  // the replica ends; another starts on the same index
  ServeProcess second({"--index", shared_->index.string(), "--session-ttl", "3"});
  auto client = second.Client();
  const auto reopened =
      client.Post("/v1/sessions/" + id + "/frames",
                  httplib::MultipartFormDataItems{
                      {"image", test::ReadFile(Photo("0012.jpg")), "0012.jpg", "image/jpeg"}});
  ASSERT_TRUE(reopened);
  ASSERT_EQ(reopened->status, 200) << reopened->body;
  EXPECT_EQ(reopened->get_header_value("X-Cwloc-Session"), "reopened");
  const json record = json::parse(reopened->body);
  EXPECT_EQ(record["pose"], fresh[0]["pose"]);  // the session's options (max-image-size) hold
  EXPECT_EQ(record["tracking"]["mode"], fresh[0]["tracking"]["mode"]);
  // From there on it is a new session's stream.
  const json next = frame(client, id, "0017.jpg");
  EXPECT_EQ(next["pose"], fresh[1]["pose"]);
  EXPECT_EQ(next["tracking"]["mode"], fresh[1]["tracking"]["mode"]);

  // Unused for --session-ttl (3 s), it ends here, and is not opened again.
  std::this_thread::sleep_for(std::chrono::milliseconds(3500));
  const json expired = frame(client, id, "0022.jpg", 404);
  EXPECT_EQ(expired["error"], "no session '" + id + "' (ended, or unused for --session-ttl)");
  // An id that carries nothing a server can open is no session.
  const json forged = frame(client, std::string(32, 'a') + ".bm9uZQ", "0022.jpg", 404);
  EXPECT_EQ(forged["error"], "no session '" + std::string(32, 'a') +
                                 ".bm9uZQ' (ended, or unused for --session-ttl)");
}

// A request shaped as the OSCP GeoPose protocol's own Python demo client shapes it
// (python/demo_client.py in github.com/OpenArCloud/oscp-geopose-protocol, written here from
// what it sends): JPEG bytes labelled RGBA32, every reading with its privacy block, empty
// readings of the other sensors, a geolocation with accuracy 0 ("unknown"), its Accept header.
// It gets 200 and the pose /v1/localize gives the same photo with the same prior.
TEST_F(ServeTest, TheProtocolsDemoClientIsAnsweredWithTheCliPose) {
  const auto geo_index = GeoreferencedIndex();
  ServeProcess server({"--index", "geo=" + geo_index.string()});
  auto client = server.Client();
  const std::string photo = test::ReadFile(Photo("0012.jpg"));
  const std::string camera = CameraOf("0012.jpg");
  const auto [model, width, height, params] = CameraParts(camera);
  const double latitude = kOrigin.latitude_deg;
  const double longitude = kOrigin.longitude_deg + 10 / (111320 * std::cos(latitude * kPi / 180));
  const double now_ms = 1765000000123.456;
  const json privacy = {{"dataRetention", json::array()},
                        {"dataAcceptableUse", json::array()},
                        {"dataSanitizationApplied", json::array()},
                        {"dataSanitizationRequested", json::array()}};
  const json no_rig = {{"rigIdentifier", ""},
                       {"rigRotation", {{"x", 0.0}, {"y", 0.0}, {"z", 0.0}, {"w", 1.0}}},
                       {"rigTranslation", {{"x", 0.0}, {"y", 0.0}, {"z", 0.0}}}};
  json camera_sensor = {
      {"type", "camera"}, {"id", "my_camera_sensor"}, {"name", ""}, {"model", ""}};
  json gps_sensor = {{"type", "geolocation"}, {"id", "my_gps_sensor"}, {"name", ""}, {"model", ""}};
  camera_sensor.update(no_rig);
  gps_sensor.update(no_rig);
  const json request = {{"type", "geopose"},
                        {"id", "9b7cbd3e-4a52-4a8e-9d6e-2f1c0a5e7b11"},
                        {"timestamp", now_ms},
                        {"sensors", {camera_sensor, gps_sensor}},
                        {"sensorReadings",
                         {{"cameraReadings",
                           {{{"timestamp", now_ms},
                             {"sensorId", "my_camera_sensor"},
                             {"privacy", privacy},
                             {"sequenceNumber", 1},
                             {"imageFormat", "RGBA32"},
                             {"size", {width, height}},
                             {"imageBytes", test::Base64(photo)},
                             {"imageOrientation", {{"mirrored", false}, {"rotation", 0.0}}},
                             {"params",
                              {{"model", model},
                               {"modelParams", params},
                               {"minMaxDepth", json::array()},
                               {"minMaxDisparity", json::array()}}}}}},
                          {"geolocationReadings",
                           {{{"timestamp", now_ms},
                             {"sensorId", "my_gps_sensor"},
                             {"privacy", privacy},
                             {"latitude", latitude},
                             {"longitude", longitude},
                             {"altitude", 42.0},
                             {"accuracy", 0.0},
                             {"altitudeAccuracy", 0.0},
                             {"heading", 0.0},
                             {"speed", 0.0}}}},
                          {"wifiReadings", json::array()},
                          {"bluetoothReadings", json::array()},
                          {"accelerometerReadings", json::array()},
                          {"gyroscopeReadings", json::array()},
                          {"magnetometerReadings", json::array()}}},
                        {"priorPoses", json::array()}};
  const httplib::Headers headers = {{"Accept", "application/vnd.oscp+json;version=2.0;"}};
  const auto answered =
      client.Post("/v1/geopose?index=geo", headers, request.dump(), "application/json");
  ASSERT_TRUE(answered);
  ASSERT_EQ(answered->status, 200) << answered->body;
  // What the client reads back: type, id, timestamp, accuracy and geopose.
  const json geopose = json::parse(answered->body);
  EXPECT_EQ(geopose["type"], "geopose");
  EXPECT_EQ(geopose["id"], "9b7cbd3e-4a52-4a8e-9d6e-2f1c0a5e7b11");
  EXPECT_TRUE(geopose["timestamp"].is_number());
  EXPECT_LT(geopose["accuracy"]["position"].get<double>(), 0.05);    // metres
  EXPECT_LT(geopose["accuracy"]["orientation"].get<double>(), 1.0);  // degrees

  char prior[96];
  std::snprintf(prior, sizeof(prior), "%.10f %.10f %.3f", latitude, longitude,
                kDefaultExifGpsRadiusM);
  const json record =
      Posted(client, "/v1/localize?index=geo",
             {{"image", photo, "0012.jpg", "image/jpeg"},
              {"options", json{{"camera", camera}, {"prior_position", prior}}.dump(), "",
               "application/json"}});
  ASSERT_TRUE(record["success"].get<bool>());
  EXPECT_EQ(geopose["geopose"]["position"]["lat"], record["geo"]["latitude_deg"]);
  EXPECT_EQ(geopose["geopose"]["position"]["lon"], record["geo"]["longitude_deg"]);
  EXPECT_EQ(geopose["geopose"]["position"]["h"], record["geo"]["height_m"]);
}

// The GeoPose answer is the result record's pose on the globe: the same position, and a
// quaternion that turns the camera's optical axis into the record's heading and pitch.
TEST_F(ServeTest, GeoPoseAndCoverageOnAGeoreferencedIndex) {
  const auto geo_index = GeoreferencedIndex();
  ServeProcess server(
      {"--index", "geo=" + geo_index.string(), "--index", "plain=" + shared_->index.string()});
  auto client = server.Client();
  const std::string photo = test::ReadFile(Photo("0002.jpg"));
  const std::string camera = CameraOf("0002.jpg");
  const auto [model, width, height, params] = CameraParts(camera);

  // A phone's fix 20 m east of the origin, 100 m accurate: the scene is within it.
  const double latitude = kOrigin.latitude_deg;
  const double longitude = kOrigin.longitude_deg + 20 / (111320 * std::cos(latitude * kPi / 180));
  json request = {
      {"id", "request-1"},
      {"timestamp", 1700000000000},
      {"type", "geopose"},
      {"sensors", {{{"id", "0"}, {"type", "camera"}}, {{"id", "1"}, {"type", "geolocation"}}}},
      {"sensorReadings",
       {{"cameraReadings",
         {{{"sensorId", "0"},
           {"imageFormat", "JPG"},
           {"size", {width, height}},
           {"imageBytes", test::Base64(photo)},
           {"params", {{"model", model}, {"modelParams", params}}}}}},
        {"geolocationReadings",
         {{{"sensorId", "1"},
           {"latitude", latitude},
           {"longitude", longitude},
           {"accuracy", 100}}}}}}};
  const auto answered = client.Post("/v1/geopose?index=geo", request.dump(), "application/json");
  ASSERT_TRUE(answered);
  ASSERT_EQ(answered->status, 200) << answered->body;
  const json geopose = json::parse(answered->body);
  EXPECT_EQ(geopose["id"], "request-1");
  EXPECT_EQ(geopose["type"], "geopose");
  EXPECT_GT(geopose["accuracy"]["position"].get<double>(), 0);
  EXPECT_LT(geopose["accuracy"]["position"].get<double>(), 0.05);  // metres

  // The same query through /v1/localize, with the prior the GeoPose request made.
  char prior[96];
  std::snprintf(prior, sizeof(prior), "%.10f %.10f %.3f", latitude, longitude, 100.0);
  const json record =
      Posted(client, "/v1/localize?index=geo",
             {{"image", photo, "0002.jpg", "image/jpeg"},
              {"options", json{{"camera", camera}, {"prior_position", prior}}.dump(), "",
               "application/json"}});
  ASSERT_TRUE(record["success"].get<bool>());
  const json& geo = record["geo"];
  EXPECT_EQ(geopose["geopose"]["position"]["lat"], geo["latitude_deg"]);
  EXPECT_EQ(geopose["geopose"]["position"]["lon"], geo["longitude_deg"]);
  EXPECT_EQ(geopose["geopose"]["position"]["h"], geo["height_m"]);
  const json& q = geopose["geopose"]["quaternion"];
  const Eigen::Quaterniond enu_from_cam(q["w"].get<double>(), q["x"].get<double>(),
                                        q["y"].get<double>(), q["z"].get<double>());
  EXPECT_NEAR(enu_from_cam.norm(), 1.0, 1e-12);
  const Eigen::Vector3d axis = enu_from_cam * Eigen::Vector3d::UnitZ();  // east, north, up
  double heading = std::atan2(axis.x(), axis.y()) * 180 / kPi;
  if (heading < 0) heading += 360;
  EXPECT_NEAR(heading, geo["heading_deg"].get<double>(), 1e-6);
  EXPECT_NEAR(std::asin(axis.z()) * 180 / kPi, geo["pitch_deg"].get<double>(), 1e-6);

  // Coverage: the scene is at the origin; nothing is at 0 N 0 E.
  const auto near = client.Get("/v1/coverage?lat=50.7753&lon=6.0839&radius=100");
  ASSERT_TRUE(near);
  const json covered = json::parse(near->body);
  EXPECT_TRUE(covered["available"].get<bool>());
  ASSERT_EQ(covered["indexes"].size(), 1u);  // the plain index is not on the globe
  EXPECT_EQ(covered["indexes"][0]["name"], "geo");
  EXPECT_EQ(covered["indexes"][0]["cameras_within"], 20);
  const json far = json::parse(client.Get("/v1/coverage?lat=0&lon=0")->body);
  EXPECT_FALSE(far["available"].get<bool>());
  EXPECT_EQ(far["indexes"][0]["cameras_within"], 0);

  // The map's colours are the index's (--point-colors), when it has them.
  const json colored = json::parse(client.Get("/v1/map?index=geo&max_points=100")->body);
  ASSERT_EQ(colored["colors"].size(), colored["points"].size());
  const Index geo_index_file = Index::Open(geo_index);
  const PointColor& first = geo_index_file.point_colors()[0];
  EXPECT_EQ(colored["colors"][0], first.rgb[0]);
  EXPECT_EQ(colored["colors"][2], first.rgb[2]);
  EXPECT_FALSE(
      json::parse(client.Get("/v1/map?index=plain&max_points=100")->body).contains("colors"));

  const auto plain = client.Post("/v1/geopose?index=plain", request.dump(), "application/json");
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->status, 400);
  EXPECT_EQ(json::parse(plain->body)["error"],
            "index 'plain' is not georeferenced (cwloc-index build --georef)");
}

TEST_F(ServeTest, InfoAndMetricsSayWhatWasServed) {
  ServeProcess server({"--index", "herz=" + shared_->index.string(), "--threads", "1", "--queue",
                       "3", "--max-features", "1500"});
  auto client = server.Client();
  const json info = json::parse(client.Get("/v1/info")->body);
  EXPECT_EQ(info["default_index"], "herz");
  EXPECT_EQ(info["indexes"][0]["images"], 20);
  EXPECT_EQ(info["threads"], 1);
  EXPECT_EQ(info["queue"], 3);
  EXPECT_EQ(info["parameters"]["max_features"], 1500);  // the server's defaults

  const json record = Posted(client, "/v1/localize",
                             {{"image", test::ReadFile(Photo("0002.jpg")), "a.jpg", "image/jpeg"}});
  EXPECT_EQ(record["parameters"]["max_features"], 1500);
  const json map = json::parse(client.Get("/v1/map?max_points=1000")->body);
  EXPECT_EQ(map["cameras"].size(), 20u);
  EXPECT_LE(map["points"].size(), 3000u);
  EXPECT_GE(map["points"].size(), 1500u);

  const std::string metrics = client.Get("/metrics")->body;
  EXPECT_NE(metrics.find("cwloc_requests_total{endpoint=\"/v1/localize\",status=\"200\"} 1\n"),
            std::string::npos)
      << metrics;
  EXPECT_NE(metrics.find("cwloc_stage_seconds_count{stage=\"extraction\"} 1\n"), std::string::npos);
  EXPECT_NE(metrics.find("cwloc_queries_total{localized=\"true\"} 1\n"), std::string::npos);
  EXPECT_NE(metrics.find("cwloc_queue_capacity 3\n"), std::string::npos);
  EXPECT_NE(metrics.find("cwloc_workers 1\n"), std::string::npos);
  const auto health = client.Get("/healthz");
  EXPECT_EQ(health->body, "ok\n");
}

// The viewer in headless Chromium (viewer_browser_test.mjs): a photo dropped through the page
// shows the pose /v1/localize gave for it. Skipped where Chromium or puppeteer-core is missing
// (tools/install-browser-deps.sh installs them, as tools/quickstart.sh test does; a skip fails
// CI: tools/check_skips.py).
TEST_F(ServeTest, TheViewerShowsThePoseTheApiReturned) {
  std::string output;
  if (test::RunCommand("command -v node", &output) != 0) GTEST_SKIP() << "no node";
  ServeProcess server({"--index", shared_->index.string()});
  auto client = server.Client();
  const json expected =
      Posted(client, "/v1/localize",
             {{"image", test::ReadFile(Photo("0002.jpg")), "0002.jpg", "image/jpeg"}});
  ASSERT_TRUE(expected["success"].get<bool>());
  std::ofstream(dir_ / "expected.json") << expected.dump();
  const int code = test::RunCommand(
      "node " + test::Quote(test::SourceDir() / "tests" / "serve" / "viewer_browser_test.mjs") +
          " --server http://127.0.0.1:" + std::to_string(server.port()) + "/ --photo " +
          test::Quote(Photo("0002.jpg")) + " --expected-json " +
          test::Quote(dir_ / "expected.json") + " --screenshot " + test::Quote(dir_ / "viewer.png"),
      &output);
  if (code == 77) GTEST_SKIP() << output;
  EXPECT_EQ(code, 0) << output;
  EXPECT_TRUE(std::filesystem::exists(dir_ / "viewer.png"));
}

// nginx with TLS in front of two replicas, configured by deploy/nginx-cwloc.conf
// (nginx_proxy_test.py): a photo's pose through the proxy is the CLI's, and neither a rolling
// restart of the replicas nor a killed replica fails a request of clients sending without
// pause; a session's frames go on. Skipped where nginx or openssl is missing (a skip fails CI).
TEST_F(ServeTest, NginxWithTlsInFrontOfTwoReplicas) {
  const std::vector<json> cli = LocalizeWithTheCli("--index " + test::Quote(shared_->index) +
                                                   " --image " + test::Quote(Photo("0002.jpg")));
  ASSERT_EQ(cli.size(), 1u);
  ASSERT_TRUE(cli[0]["success"].get<bool>());
  std::ofstream(dir_ / "expected.json") << cli[0].dump();
  std::string output;
  const int code = test::RunCommand(
      "python3 " + test::Quote(test::SourceDir() / "tests" / "serve" / "nginx_proxy_test.py") +
          " --serve " + test::Quote(test::ToolPath("cwloc-serve")) + " --index " +
          test::Quote(shared_->index) + " --photo " + test::Quote(Photo("0002.jpg")) +
          " --expected-json " + test::Quote(dir_ / "expected.json") + " --config " +
          test::Quote(test::SourceDir() / "deploy" / "nginx-cwloc.conf") + " --work " +
          test::Quote(dir_ / "nginx"),
      &output);
  if (code == 77) GTEST_SKIP() << output;
  EXPECT_EQ(code, 0) << output;
  std::cout << output;
}

}  // namespace
}  // namespace cwloc
