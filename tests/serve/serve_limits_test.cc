// cwloc-serve under abuse and load: malformed requests get a 4xx naming the problem and crash
// nothing, a full queue answers 503 at once, a reload under load fails no request, SIGTERM
// finishes the requests in flight, tokens and CORS (docs/serve.md, "Limits").
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>
#include <thread>

#include "app/photo_query.h"
#include "tests/serve/serve_process.h"
#include "tests/shared_data_index.h"

namespace cwloc {
namespace {

using nlohmann::json;
using test::ServeProcess;

class ServeLimitsTest : public testing::Test {
 protected:
  void SetUp() override {
    shared_ = test::BuildSharedDataIndex("herz_jesu_p25");
    if (!shared_) GTEST_SKIP() << "no ../shared/data/herz_jesu_p25";
    photo_ = test::ReadFile(shared_->data / "query_images" / "0002.jpg");
  }

  // A query's features in the binary layout, and its camera.
  std::string BinaryFeatures() const {
    PhotoOptions small;  // as a device extracts them, at a smaller size
    small.max_image_size = 1024;
    const Query query =
        LoadPhotoQuery(shared_->data / "query_images" / "0007.jpg", "0007.jpg", small);
    return test::BinaryFeatureBody(query);
  }
  static constexpr const char* kCamera =
      R"({"camera": "SIMPLE_RADIAL 1536 1024 1375.7714362748345 768 512 -0.0008"})";

  std::optional<test::SharedDataIndex> shared_;
  std::string photo_;
  test::TempDir dir_;
};

struct Malformed {
  std::string method, path, content_type, body;
  httplib::MultipartFormDataItems parts;
  int status;
  std::string error;
};

// Each kind of malformed request is sent this many times, ~1,000 requests over this file's
// kinds: they must crash nothing.
constexpr int kRounds = 38;

class ServeMalformedTest : public ServeLimitsTest {
 protected:
  void SetUp() override {
    ServeLimitsTest::SetUp();
    if (IsSkipped()) return;
    server_.emplace(std::vector<std::string>{"--index", "herz=" + shared_->index.string(),
                                             "--max-body-mb", "1", "--max-image-pixels",
                                             "40000000"});
  }

  // Sends each request `rounds` times and checks every answer's status and error; then the
  // server still answers.
  void ExpectEachRefused(const std::vector<Malformed>& cases, int rounds = kRounds) {
    auto client = server_->Client();
    for (int round = 0; round < rounds; ++round) {
      for (const Malformed& c : cases) {
        httplib::Result response = c.method == "GET"      ? client.Get(c.path)
                                   : c.method == "DELETE" ? client.Delete(c.path)
                                   : !c.parts.empty()     ? client.Post(c.path, c.parts)
                                                      : client.Post(c.path, c.body, c.content_type);
        ASSERT_TRUE(response) << c.method << " " << c.path << ": "
                              << httplib::to_string(response.error());
        ASSERT_EQ(response->status, c.status) << c.method << " " << c.path << " " << response->body;
        const json body = json::parse(response->body);
        ASSERT_EQ(body["error"], c.error) << c.method << " " << c.path;
        ASSERT_EQ(body["status"], c.status);
      }
    }
    EXPECT_EQ(client.Get("/healthz")->status, 200);
  }

  std::optional<ServeProcess> server_;
};

TEST_F(ServeMalformedTest, BodiesThatAreNoQueryGet400) {
  ExpectEachRefused({
      {"POST",
       "/v1/localize",
       "image/jpeg",
       "",
       {},
       400,
       "empty body: send a JPEG or PNG, features, or multipart/form-data with an 'image' part"},
      {"POST",
       "/v1/localize",
       "image/jpeg",
       "not a photo",
       {},
       400,
       "body: not a JPEG or PNG image"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"photo", photo_, "a.jpg", "image/jpeg"}},
       400,
       "multipart request without an 'image' or a 'features' part"},
  });
  // A truncated photo names the decoder's problem.
  auto client = server_->Client();
  const auto truncated = client.Post("/v1/localize", photo_.substr(0, 2000), "image/jpeg");
  ASSERT_TRUE(truncated);
  EXPECT_EQ(truncated->status, 400);
  EXPECT_EQ(json::parse(truncated->body)["error"].get<std::string>().rfind("body: ", 0), 0u)
      << truncated->body;
}

TEST_F(ServeMalformedTest, ABodyOverMaxBodyMbGets413) {
  // Once: each costs a megabyte.
  ExpectEachRefused(
      {
          {"POST",
           "/v1/localize",
           "image/jpeg",
           std::string(1100000, 'x'),
           {},
           413,
           "the body is too large: 1100000 bytes, over --max-body-mb (1048576 bytes)"},
      },
      1);
}

TEST_F(ServeMalformedTest, BadOptionsGet400NamingTheOption) {
  // A session's options travel in its id (serve/sessions.h): at most 2 KiB.
  const std::string long_options = R"({"name": ")" + std::string(2100, 'a') + R"("})";
  ExpectEachRefused({
      {"POST",
       "/v1/sessions",
       "application/json",
       long_options,
       {},
       400,
       "session options: " + std::to_string(long_options.size()) +
           " bytes, over 2048 (they travel in the session's id)"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", "{max", "", ""}},
       400,
       "options: not valid JSON"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", "[1]", "", ""}},
       400,
       "options: expected a JSON object"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", R"({"max-featurs": 10})", "", ""}},
       400,
       "options: unknown option 'max-featurs'"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", R"({"nb": 0})", "", ""}},
       400,
       "options: 'nb': --nb 0: expected at least 1"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", R"({"nb": [1]})", "", ""}},
       400,
       "options: 'nb': expected a number, a string or true/false"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", R"({"camera": "PINHOLE 10"})", "", ""}},
       400,
       "options: 'camera': expected a positive image height (at most 1000000)"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""},
        {"options", R"({"camera": "SIMPLE_PINHOLE 1536 1024 1000 768 512", "focal": 900})", "",
         ""}},
       400,
       "options: 'camera' excludes 'focal' and 'image_size'"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"image", photo_, "", ""}, {"options", R"({"max-image-pixels": 50000000})", "", ""}},
       400,
       "options: 'max-image-pixels' 50000000: this server allows at most 40000000"},
  });
}

TEST_F(ServeMalformedTest, BadFeaturesGet400NamingTheProblem) {
  ExpectEachRefused({
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"features", "CWLF", "", ""}},
       400,
       "part 'features': features need a camera: give options 'camera' (\"MODEL W H PARAMS\") "
       "or 'image_size' (\"W H\")"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"features", std::string("CWLF\1\0\0\0\2\0\0\0", 12) + "abc", "", ""},
        {"options", kCamera, "", ""}},
       400,
       "part 'features': 2 binary features take 284 bytes, got 15"},
      {"POST",
       "/v1/localize",
       "",
       "",
       {{"features", "12 64\n", "f.txt", "text/plain"}, {"options", kCamera, "", ""}},
       400,
       "part 'features':1: descriptors have 64 dimensions, expected 128"},
  });
}

TEST_F(ServeMalformedTest, AnUnknownIndexEndpointOrSessionGets404) {
  ExpectEachRefused({
      {"POST",
       "/v1/localize?index=nope",
       "image/jpeg",
       photo_,
       {},
       404,
       "no index named 'nope' (GET /v1/info lists them)"},
      {"GET", "/v1/nothing", "", "", {}, 404, "no such endpoint: GET /v1/nothing"},
      {"POST",
       "/v1/sessions/abc/frames",
       "image/jpeg",
       photo_,
       {},
       404,
       "no session 'abc' (ended, or unused for --session-ttl)"},
      {"DELETE", "/v1/sessions/abc", "", "", {}, 404, "no session 'abc'"},
  });
}

TEST_F(ServeMalformedTest, BadGeoPoseRequestsGet400) {
  const std::string geopose_head =
      R"({"id": "x", "sensorReadings": {"cameraReadings": [{"imageFormat": )";
  ExpectEachRefused({
      {"POST", "/v1/geopose", "application/json", "{", {}, 400, "geopose: not valid JSON"},
      {"POST",
       "/v1/geopose",
       "application/json",
       geopose_head + R"("BMP", "size": [4, 4], "imageBytes": "AAAA"}]}})",
       {},
       400,
       "geopose: 'cameraReadings'[0]: 'imageFormat' must be JPG, PNG, RGBA32 or GRAY8 (cwloc "
       "reads no other)"},
      {"POST",
       "/v1/geopose",
       "application/json",
       geopose_head + R"("JPG", "size": [4, 4], "imageBytes": "a*b"}]}})",
       {},
       400,
       "geopose: 'cameraReadings'[0].imageBytes: not base64 (a character outside A-Z a-z 0-9 + "
       "/)"},
      {"POST",
       "/v1/geopose",
       "application/json",
       geopose_head + R"("GRAY8", "size": [4, 4], "imageBytes": "AAAA"}]}})",
       {},
       400,
       "geopose: 'cameraReadings'[0]: GRAY8 of 4 x 4 needs 16 bytes, got 3"},
  });
}

TEST_F(ServeMalformedTest, BadCoverageAndMapParametersGet400) {
  ExpectEachRefused({
      {"GET", "/v1/coverage?lon=3", "", "", {}, 400, "give ?lat="},
      {"GET", "/v1/coverage?lat=north&lon=3", "", "", {}, 400, "?lat=north: expected a number"},
      {"GET", "/v1/map?max_points=-1", "", "", {}, 400, "?max_points=: expected 0 to 5000000"},
  });
}

TEST_F(ServeMalformedTest, ReloadOverHttpWithoutATokenGets403) {
  ExpectEachRefused({
      {"POST",
       "/v1/admin/reload",
       "",
       "",
       {},
       403,
       "reloading over HTTP needs --token-file (SIGHUP reloads too)"},
  });
}

// Six photos at once on one worker with room for one more in the queue: the rest are turned
// away at once with 503 and Retry-After, none is lost.
// A gauge of GET /metrics ("cwloc_workers_busy 1"), or -1.
double Gauge(ServeProcess& server, const std::string& name) {
  auto client = server.Client();
  const auto response = client.Get("/metrics");
  if (!response) return -1;
  const size_t at = response->body.find("\n" + name + " ");
  return at == std::string::npos ? -1 : std::stod(response->body.substr(at + name.size() + 2));
}

// Waits (at most 30 s, a loaded machine) until the gauge has this value.
bool AwaitGauge(ServeProcess& server, const std::string& name, double value) {
  for (int i = 0; i < 3000; ++i) {
    if (Gauge(server, name) == value) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

// Without --queue, 16 queries may wait per worker (kQueuedQueriesPerWorker; docs/benchmarks.md,
// "Service, round three"): the info and the metrics say the capacity.
TEST_F(ServeLimitsTest, TheDefaultQueueHolds16QueriesPerWorker) {
  ServeProcess server({"--index", shared_->index.string(), "--threads", "2"});
  auto client = server.Client();
  EXPECT_EQ(json::parse(client.Get("/v1/info")->body)["queue"], 32);
  EXPECT_EQ(Gauge(server, "cwloc_queue_capacity"), 32);
}

TEST_F(ServeLimitsTest, AFullQueueAnswers503AtOnce) {
  ServeProcess server({"--index", shared_->index.string(), "--threads", "1", "--queue", "1"});
  std::vector<int> statuses(6, 0);
  std::vector<std::string> bodies(6), retry(6);
  std::vector<std::thread> clients;
  const auto post = [&](size_t i) {
    auto client = server.Client();
    const auto response = client.Post("/v1/localize", photo_, "image/jpeg");
    if (!response) return;
    statuses[i] = response->status;
    bodies[i] = response->body;
    retry[i] = response->get_header_value("Retry-After");
  };
  // One query takes the worker and one the queue's place (the worker is busy for the photo's
  // extraction, hundreds of ms, and waits for nothing); then the others find the queue full.
  clients.emplace_back(post, 0);
  ASSERT_TRUE(AwaitGauge(server, "cwloc_workers_busy", 1));
  clients.emplace_back(post, 1);
  ASSERT_TRUE(AwaitGauge(server, "cwloc_queue_depth", 1));
  for (size_t i = 2; i < statuses.size(); ++i) clients.emplace_back(post, i);
  for (std::thread& client : clients) client.join();
  int ok = 0, busy = 0;
  for (size_t i = 0; i < statuses.size(); ++i) {
    if (statuses[i] == 200) {
      ++ok;
      EXPECT_TRUE(json::parse(bodies[i])["success"].get<bool>());
    } else {
      ASSERT_EQ(statuses[i], 503) << bodies[i];
      ++busy;
      EXPECT_EQ(retry[i], "1");
      EXPECT_EQ(json::parse(bodies[i])["error"],
                "busy: 1 queries wait already (--queue); retry later");
    }
  }
  // The first two are answered; of the four that came while both were taken, a photo's
  // extraction outlasts most: at least one is refused at once.
  EXPECT_EQ(statuses[0], 200);
  EXPECT_EQ(statuses[1], 200);
  EXPECT_GE(ok, 2);
  EXPECT_GE(busy, 1);
  // With a deadline, a request no worker starts in time gets 503 too.
  ServeProcess deadline(
      {"--index", shared_->index.string(), "--threads", "1", "--budget-ms", "50"});
  std::vector<int> expired(4, 0);
  clients.clear();
  for (size_t i = 0; i < expired.size(); ++i) {
    // The first takes the worker for a photo's extraction (hundreds of ms); the others come
    // while it works, and their 50 ms run out in the queue.
    if (i == 1) std::this_thread::sleep_for(std::chrono::milliseconds(100));
    clients.emplace_back([&, i] {
      auto client = deadline.Client();
      const auto response = client.Post("/v1/localize", photo_, "image/jpeg");
      if (!response) return;
      expired[i] = response->status;
      if (response->status == 503) {
        EXPECT_EQ(json::parse(response->body)["error"],
                  "busy: no worker was free early enough to answer within --budget-ms; retry "
                  "later");
      }
    });
  }
  for (std::thread& client : clients) client.join();
  // On a loaded machine a request may come after the photo before it is done: then it finds
  // the worker free. Some request always waits past its budget.
  const auto answered = std::count(expired.begin(), expired.end(), 200);
  EXPECT_GE(answered, 1);
  EXPECT_EQ(std::count(expired.begin(), expired.end(), 503), 4 - answered);
  EXPECT_LE(answered, 3);
}

// Two clients keep sending features while the index file is replaced and reloaded three times
// (SIGHUP twice, then POST /v1/admin/reload): every request is answered 200 with the same pose.
TEST_F(ServeLimitsTest, AReloadUnderLoadFailsNoRequest) {
  // Reloads alternate between two indexes of the scene that answer the query differently:
  // the full descriptors and 32-byte codes.
  const auto compact = test::BuildSharedDataIndex("herz_jesu_p25", 32);
  ASSERT_TRUE(compact);
  const auto served = dir_ / "served.cwl";
  std::filesystem::copy_file(shared_->index, served);
  std::ofstream(dir_ / "token") << "secret-token\n";
  ServeProcess server(
      {"--index", served.string(), "--threads", "2", "--token-file", (dir_ / "token").string()});
  const std::string features = BinaryFeatures();
  const httplib::Headers authorized = {{"Authorization", "Bearer secret-token"}};
  const auto pose_from = [&](const ServeProcess& from) {
    const auto response =
        from.Client().Post("/v1/localize", authorized,
                           httplib::MultipartFormDataItems{{"features", features, "f.bin", ""},
                                                           {"options", kCamera, "", ""}});
    if (!response || response->status != 200) return std::string("no answer");
    return json::parse(response->body)["pose"].dump();
  };
  std::string compact_pose;
  {
    ServeProcess compact_server(
        {"--index", compact->index.string(), "--token-file", (dir_ / "token").string()});
    compact_pose = pose_from(compact_server);
  }
  const std::string full_pose = pose_from(server);
  ASSERT_NE(compact_pose, full_pose);  // else the test could not tell the indexes apart
  std::atomic<bool> stop{false};
  std::atomic<int> answered{0};
  std::mutex mutex;
  std::vector<std::string> failures;
  std::set<std::string> poses;
  std::vector<std::thread> clients;
  for (int c = 0; c < 2; ++c) {
    clients.emplace_back([&] {
      auto client = server.Client();
      while (!stop) {
        httplib::MultipartFormDataItems items = {{"features", features, "f.bin", ""},
                                                 {"options", kCamera, "", ""}};
        const auto response = client.Post("/v1/localize", authorized, items);
        std::lock_guard<std::mutex> lock(mutex);
        if (!response || response->status != 200) {
          failures.push_back(response ? response->body : httplib::to_string(response.error()));
        } else {
          poses.insert(json::parse(response->body)["pose"].dump());
          ++answered;
        }
      }
    });
  }
  auto client = server.Client();
  const auto generation = [&] {
    const auto info = client.Get("/v1/info", authorized);
    if (!info || info->status != 200) {
      ADD_FAILURE() << "GET /v1/info: " << (info ? info->body : httplib::to_string(info.error()))
                    << server.Log();
      return -1;
    }
    return json::parse(info->body)["indexes"][0]["generation"].get<int>();
  };
  for (int round = 1; round <= 3; ++round) {
    const int before = answered;
    while (answered < before + 5) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    const bool to_compact = round % 2 == 1;
    const auto next = dir_ / "next.cwl";
    std::filesystem::copy_file(to_compact ? compact->index : shared_->index, next);
    std::filesystem::rename(next, served);  // as a deployment replaces the file
    if (round < 3) {
      ::kill(server.pid(), SIGHUP);
      int now = 0;
      while ((now = generation()) != round && now >= 0)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      ASSERT_EQ(now, round);
    } else {
      const auto reloaded = client.Post("/v1/admin/reload", authorized, "", "text/plain");
      ASSERT_TRUE(reloaded);
      EXPECT_EQ(reloaded->status, 200) << reloaded->body;
      EXPECT_EQ(generation(), 3);
    }
    // A request after the reload is answered from the new index.
    EXPECT_EQ(pose_from(server), to_compact ? compact_pose : full_pose) << "round " << round;
  }
  const int before = answered;
  while (answered < before + 5) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  stop = true;
  for (std::thread& c : clients) c.join();
  EXPECT_TRUE(failures.empty()) << failures.size() << " failed, the first: " << failures[0];
  EXPECT_GE(answered, 20);
  EXPECT_EQ(poses, (std::set<std::string>{full_pose, compact_pose}));  // each index's own
  // A file that fails to open leaves the old index serving. (It is renamed into place: a file
  // written over in place would change the pages the server has mapped, docs/serve.md.)
  std::ofstream(dir_ / "broken.cwl") << "not an index";
  std::filesystem::rename(dir_ / "broken.cwl", served);
  const auto failed = client.Post("/v1/admin/reload", authorized, "", "text/plain");
  ASSERT_TRUE(failed);
  EXPECT_EQ(failed->status, 500);
  EXPECT_EQ(generation(), 3);
  EXPECT_EQ(client
                .Post("/v1/localize", authorized,
                      httplib::MultipartFormDataItems{{"features", features, "f.bin", ""},
                                                      {"options", kCamera, "", ""}})
                ->status,
            200);
}

TEST_F(ServeLimitsTest, SigtermFinishesTheRequestsInFlight) {
  ServeProcess server({"--index", shared_->index.string(), "--threads", "1"});
  int status = 0;
  bool success = false;
  std::thread client([&] {
    auto http = server.Client();
    const auto response = http.Post("/v1/localize", photo_, "image/jpeg");
    if (!response) return;
    status = response->status;
    success = json::parse(response->body)["success"].get<bool>();
  });
  // Wait until a worker runs it, then ask the server to stop.
  auto http = server.Client();
  while (http.Get("/metrics")->body.find("cwloc_workers_busy 1\n") == std::string::npos)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  const int exit_code = server.Stop();
  client.join();
  EXPECT_EQ(status, 200);
  EXPECT_TRUE(success);
  EXPECT_EQ(exit_code, 0) << server.Log();
  EXPECT_NE(server.Log().find("SIGTERM: finishing the requests in flight"), std::string::npos);
  EXPECT_FALSE(http.Get("/healthz"));  // nobody listens any more
}

TEST_F(ServeLimitsTest, TokensAndCors) {
  std::ofstream(dir_ / "token") << "  s3cret \n";
  ServeProcess locked(
      {"--index", shared_->index.string(), "--token-file", (dir_ / "token").string()});
  auto client = locked.Client();
  const auto refused = client.Get("/v1/info");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 401);
  EXPECT_EQ(json::parse(refused->body)["error"], "this server needs 'Authorization: Bearer TOKEN'");
  EXPECT_EQ(client.Get("/v1/info", {{"Authorization", "Bearer wrong"}})->status, 401);
  EXPECT_EQ(client.Get("/v1/info", {{"Authorization", "Bearer s3cret"}})->status, 200);
  // The viewer's files hold no map data: served without the token, built into the binary.
  const auto page = client.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<title>cwloc map viewer</title>"), std::string::npos);
  EXPECT_EQ(page->body, test::ReadFile(test::SourceDir() / "serve" / "viewer" / "index.html"));
  const auto three = client.Get("/viewer/three.min.js");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->body.size(),
            std::filesystem::file_size("/usr/share/javascript/three/build/three.min.js"));
  EXPECT_EQ(three->get_header_value("Content-Encoding"), "");  // never compressed
  EXPECT_FALSE(refused->has_header("Access-Control-Allow-Origin"));

  ServeProcess open({"--index", shared_->index.string(), "--allow-origin", "https://app.example"});
  auto browser = open.Client();
  const auto preflight = browser.Options("/v1/localize");
  ASSERT_TRUE(preflight);
  EXPECT_EQ(preflight->status, 204);
  EXPECT_EQ(preflight->get_header_value("Access-Control-Allow-Origin"), "https://app.example");
  EXPECT_EQ(browser.Get("/v1/info")->get_header_value("Access-Control-Allow-Origin"),
            "https://app.example");
}

TEST_F(ServeLimitsTest, BadArgumentsExitWithAMessage) {
  const std::string serve = test::Quote(test::ToolPath("cwloc-serve"));
  const std::string index = test::Quote(shared_->index);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "--index is required"},
      {"--index /nonexistent.cwl", "cwloc-serve: error: /nonexistent.cwl"},
      {"--index " + index + " --listen nonsense",
       "cwloc-serve: error: --listen 'nonsense': expected HOST:PORT"},
      {"--index " + index + " --listen 127.0.0.1:70000",
       "cwloc-serve: error: --listen '127.0.0.1:70000': the port must be a number in 0..65535"},
      {"--index a=" + index + " --index a=" + index,
       "cwloc-serve: error: --index: two indexes named 'a' (give NAME=FILE)"},
      {"--index " + index + " --nb 0", "cwloc-serve: error: --nb 0: expected at least 1"},
      {"--index " + index + " --token-file /nonexistent",
       "cwloc-serve: error: /nonexistent: cannot read the token file"},
  };
  for (const auto& [arguments, message] : cases) {
    std::string output;
    EXPECT_EQ(test::RunCommand(serve + " " + arguments, &output), 2) << arguments;
    EXPECT_NE(output.find(message), std::string::npos) << arguments << ": " << output;
  }
}

}  // namespace
}  // namespace cwloc
