// Proves that the real colmap binary reads the databases DatabaseWriter writes: colmap's
// exhaustive matcher must find the correspondences we planted, and our reader must still
// read the file after colmap opened (and possibly upgraded) it.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <vector>

#include "colmap/database.h"
#include "tests/test_util.h"

namespace cwloc::colmap {
namespace {

constexpr int kNumImages = 4;
constexpr int kNumShared = 300;                // features every image sees
constexpr int kNumUnique = 40;                 // clutter seen by one image only
constexpr int64_t kMaxNumImages = 2147483647;  // COLMAP: pair_id = id1 * kMaxNumImages + id2

// A SIFT-like descriptor: non-negative, L2 norm 512 as COLMAP's matcher
// assumes (it maps dot products to angles with 1 / 512^2).
std::array<float, kDescriptorDim> RandomSiftLike() {
  std::normal_distribution<float> normal(0, 1);
  std::array<float, kDescriptorDim> d;
  for (float& v : d) v = std::abs(normal(test::Rng()));
  const float norm = std::sqrt(std::inner_product(d.begin(), d.end(), d.begin(), 0.0f));
  for (float& v : d) v *= 512 / norm;
  return d;
}

// Quantizes a noisy copy of `d` (renormalized to 512) into one descriptor row.
void NoisyRow(const std::array<float, kDescriptorDim>& d, uint8_t* out) {
  std::normal_distribution<float> noise(0, 2);
  std::array<float, kDescriptorDim> v;
  for (int i = 0; i < kDescriptorDim; ++i) v[i] = std::max(0.0f, d[i] + noise(test::Rng()));
  const float norm = std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0f));
  for (int i = 0; i < kDescriptorDim; ++i) {
    out[i] = static_cast<uint8_t>(std::min(255.0f, std::round(v[i] * 512 / norm)));
  }
}

struct Scene {
  std::vector<DatabaseImage> images;
  // Per image, per keypoint row: which scene feature it shows (-1 for clutter).
  std::map<image_t, std::vector<int>> feature_of_row;
};

// A planar scene seen by kNumImages cameras under small similarity transforms, written with
// DatabaseWriter. Every image lists its features in its own random order.
Scene WriteScene(const std::filesystem::path& path) {
  std::uniform_real_distribution<float> uniform(0, 1);
  std::vector<std::array<float, kDescriptorDim>> descriptors;
  std::vector<std::array<float, 2>> positions;
  for (int i = 0; i < kNumShared + kNumImages * kNumUnique; ++i) {
    descriptors.push_back(RandomSiftLike());
    positions.push_back({150 + 700 * uniform(test::Rng()), 150 + 500 * uniform(test::Rng())});
  }

  Scene scene;
  DatabaseWriter writer(path);
  writer.WriteCamera({1, CameraModelId::kSimpleRadial, 1000, 800, {900, 500, 400, 0}});
  for (image_t image_id = 1; image_id <= kNumImages; ++image_id) {
    const DatabaseImage image{image_id, "image" + std::to_string(image_id) + ".jpg", 1};
    writer.WriteImage(image);
    scene.images.push_back(image);

    std::vector<int> features(kNumShared);
    std::iota(features.begin(), features.end(), 0);
    for (int u = 0; u < kNumUnique; ++u) {
      features.push_back(kNumShared + static_cast<int>(image_id - 1) * kNumUnique + u);
    }
    std::shuffle(features.begin(), features.end(), test::Rng());

    const float angle = 0.08f * (static_cast<float>(image_id) - 2.5f);
    const float scale = 1 + 0.05f * (static_cast<float>(image_id) - 2.5f);
    const float shift = 15.0f * static_cast<float>(image_id);
    std::vector<Keypoint> keypoints;
    Descriptors rows;
    rows.rows = static_cast<uint32_t>(features.size());
    rows.data.resize(features.size() * kDescriptorDim);
    for (size_t r = 0; r < features.size(); ++r) {
      const int f = features[r];
      const float dx = positions[f][0] - 500, dy = positions[f][1] - 400;
      Keypoint kp;
      kp.x = 500 + shift + scale * (std::cos(angle) * dx - std::sin(angle) * dy);
      kp.y = 400 + scale * (std::sin(angle) * dx + std::cos(angle) * dy);
      kp.a11 = kp.a22 = 3 * std::cos(angle);
      kp.a21 = 3 * std::sin(angle);
      kp.a12 = -kp.a21;
      keypoints.push_back(kp);
      NoisyRow(descriptors[f], rows.data.data() + r * kDescriptorDim);
      scene.feature_of_row[image_id].push_back(f < kNumShared ? f : -1);
    }
    writer.WriteKeypoints(image_id, keypoints);
    writer.WriteDescriptors(image_id, rows);
  }
  writer.Commit();
  return scene;
}

// pair_id -> rows x 2 uint32 matches, as colmap stored them.
std::map<int64_t, std::vector<std::array<uint32_t, 2>>> ReadMatches(
    const std::filesystem::path& path, const char* table) {
  std::map<int64_t, std::vector<std::array<uint32_t, 2>>> matches;
  // colmap has finished: immutable reads its WAL-mode file without creating -wal/-shm.
  const std::string uri = "file:" + path.string() + "?immutable=1";
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(uri.c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr),
            SQLITE_OK);
  const std::string sql = std::string("SELECT pair_id, rows, cols, data FROM ") + table;
  sqlite3_stmt* stmt = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    const int64_t rows = sqlite3_column_int64(stmt, 1);
    EXPECT_EQ(sqlite3_column_int64(stmt, 2), 2);
    EXPECT_EQ(sqlite3_column_bytes(stmt, 3), rows * 2 * 4);
    std::vector<std::array<uint32_t, 2>>& pairs = matches[sqlite3_column_int64(stmt, 0)];
    pairs.resize(static_cast<size_t>(rows));
    if (rows > 0) std::memcpy(pairs.data(), sqlite3_column_blob(stmt, 3), pairs.size() * 8);
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return matches;
}

struct DatabaseContent {
  std::vector<Camera> cameras;
  std::vector<DatabaseImage> images;
  std::vector<std::vector<Keypoint>> keypoints;
  std::vector<std::vector<uint8_t>> descriptors;
  bool operator==(const DatabaseContent&) const = default;
};

DatabaseContent ReadContent(const std::filesystem::path& path) {
  const DatabaseReader reader(path);
  DatabaseContent content{reader.ReadAllCameras(), reader.ReadAllImages(), {}, {}};
  for (const DatabaseImage& image : content.images) {
    ImageFeatures features = reader.ReadFeatures(image.image_id);
    content.keypoints.push_back(std::move(features.keypoints));
    content.descriptors.push_back(std::move(features.descriptors.data));
  }
  return content;
}

TEST(DatabaseCompatTest, ColmapMatchesWhatWeWrite) {
  std::string output;
  if (test::RunCommand("command -v colmap", &output) != 0) {
    GTEST_SKIP()
        << "colmap is not on PATH; skipping the compatibility test against the real COLMAP";
  }
  test::TempDir dir;
  const std::filesystem::path original = dir / "ours.db";
  const std::filesystem::path copy = dir / "copy" / "database.db";
  const Scene scene = WriteScene(original);
  std::filesystem::create_directories(copy.parent_path());
  std::filesystem::copy_file(original, copy);

  const auto start = std::chrono::steady_clock::now();
  const int exit_code = test::RunCommand(
      "QT_QPA_PLATFORM=offscreen timeout 120 colmap exhaustive_matcher --database_path '" +
          copy.string() + "' --SiftMatching.use_gpu 0 --SiftMatching.num_threads 1",
      &output);
  ASSERT_EQ(exit_code, 0) << output;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("colmap_seconds", std::to_string(seconds));

  // Every pair of images shares kNumShared features: colmap must find most of them, and the
  // rows it matched must show the same scene feature.
  const auto matches = ReadMatches(copy, "matches");
  const auto verified = ReadMatches(copy, "two_view_geometries");
  std::set<int64_t> pairs_seen;
  for (image_t id1 = 1; id1 <= kNumImages; ++id1) {
    for (image_t id2 = id1 + 1; id2 <= kNumImages; ++id2) {
      const int64_t pair_id = int64_t{id1} * kMaxNumImages + id2;
      pairs_seen.insert(pair_id);
      SCOPED_TRACE("images " + std::to_string(id1) + " and " + std::to_string(id2));
      ASSERT_TRUE(matches.count(pair_id));
      const auto& pair_matches = matches.at(pair_id);
      int correct = 0;
      for (const auto& [row1, row2] : pair_matches) {
        ASSERT_LT(row1, scene.feature_of_row.at(id1).size());
        ASSERT_LT(row2, scene.feature_of_row.at(id2).size());
        const int f1 = scene.feature_of_row.at(id1)[row1];
        correct += f1 >= 0 && f1 == scene.feature_of_row.at(id2)[row2];
      }
      EXPECT_GE(correct, kNumShared * 9 / 10);
      EXPECT_GE(correct, static_cast<int>(pair_matches.size()) * 95 / 100);
      ASSERT_TRUE(verified.count(pair_id));
      EXPECT_GE(verified.at(pair_id).size(), size_t{kNumShared} * 8 / 10);
    }
  }
  for (const auto& [pair_id, pair_matches] : matches) {
    EXPECT_TRUE(pairs_seen.count(pair_id)) << "unexpected pair_id " << pair_id;
  }

  // colmap switched the copy to WAL mode; our reader still reads it, identically, and
  // leaves no side files.
  EXPECT_EQ(ReadContent(copy), ReadContent(original));
  std::set<std::string> entries;
  for (const auto& entry : std::filesystem::directory_iterator(copy.parent_path())) {
    entries.insert(entry.path().filename().string());
  }
  EXPECT_EQ(entries, std::set<std::string>{"database.db"});
}

}  // namespace
}  // namespace cwloc::colmap
