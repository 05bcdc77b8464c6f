#include "colmap/database.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "base/error.h"
#include "tests/test_util.h"

namespace cwloc::colmap {
namespace {

// A read-write connection for building databases the writer cannot make (old keypoint
// layouts, newer schemas, corrupt rows).
class RawDb {
 public:
  explicit RawDb(const std::filesystem::path& path) {
    EXPECT_EQ(sqlite3_open(path.c_str(), &db_), SQLITE_OK);
  }
  ~RawDb() { sqlite3_close(db_); }
  RawDb(const RawDb&) = delete;
  RawDb& operator=(const RawDb&) = delete;

  void Exec(const std::string& sql) {
    char* error = nullptr;
    const int rc = sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error);
    ASSERT_EQ(rc, SQLITE_OK) << sql << ": " << (error ? error : "");
    sqlite3_free(error);
  }

  // Runs `sql` with one blob bound to ?1.
  void ExecWithBlob(const std::string& sql, const void* data, size_t bytes) {
    sqlite3_stmt* stmt = nullptr;
    ASSERT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    sqlite3_bind_blob64(stmt, 1, data, bytes, SQLITE_TRANSIENT);
    EXPECT_EQ(sqlite3_step(stmt), SQLITE_DONE) << sql;
    sqlite3_finalize(stmt);
  }

  int64_t QueryInt(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    int64_t value = -1;
    if (sqlite3_step(stmt) == SQLITE_ROW) value = sqlite3_column_int64(stmt, 0);
    sqlite3_finalize(stmt);
    return value;
  }

  std::vector<std::string> QueryStrings(const std::string& sql) {
    sqlite3_stmt* stmt = nullptr;
    EXPECT_EQ(sqlite3_prepare_v2(db_, sql.c_str(), -1, &stmt, nullptr), SQLITE_OK) << sql;
    std::vector<std::string> values;
    while (sqlite3_step(stmt) == SQLITE_ROW) {
      const unsigned char* text = sqlite3_column_text(stmt, 0);
      values.emplace_back(text ? reinterpret_cast<const char*>(text) : "NULL");
    }
    sqlite3_finalize(stmt);
    return values;
  }

 private:
  sqlite3* db_ = nullptr;
};

std::vector<Keypoint> RandomKeypoints(size_t n) {
  std::uniform_real_distribution<float> pos(0, 1000), angle(-3.1f, 3.1f), scale(1, 20);
  std::vector<Keypoint> keypoints(n);
  for (Keypoint& kp : keypoints) {
    kp.x = pos(test::Rng());
    kp.y = pos(test::Rng());
    const float s = scale(test::Rng()), o = angle(test::Rng());
    kp.a11 = s * std::cos(o);
    kp.a12 = -s * std::sin(o) * 1.1f;  // not a similarity: 6 columns must survive exactly
    kp.a21 = s * std::sin(o);
    kp.a22 = s * std::cos(o) * 0.9f;
  }
  return keypoints;
}

Descriptors RandomDescriptors(uint32_t rows) {
  std::uniform_int_distribution<int> byte(0, 255);
  Descriptors descriptors;
  descriptors.rows = rows;
  descriptors.data.resize(size_t{rows} * kDescriptorDim);
  for (uint8_t& b : descriptors.data) b = static_cast<uint8_t>(byte(test::Rng()));
  return descriptors;
}

// Content of the small database most tests use: two cameras, four images (image 4 has no
// features at all), keypoint and descriptor rows equal per image.
struct SmallDatabase {
  std::vector<Camera> cameras;
  std::vector<DatabaseImage> images;
  std::map<image_t, std::vector<Keypoint>> keypoints;
  std::map<image_t, Descriptors> descriptors;

  SmallDatabase() {
    cameras.push_back({1, CameraModelId::kSimpleRadial, 1536, 1024, {1375.5, 768, 512, -0.01}});
    cameras.push_back({2, CameraModelId::kPinhole, 640, 480, {500, 501, 320, 240}});
    images = {{1, "a.jpg", 1}, {2, "b.jpg", 1}, {3, "sub/c.jpg", 2}, {4, "d.jpg", 2}};
    const uint32_t counts[] = {10, 37, 1};
    for (image_t id = 1; id <= 3; ++id) {
      keypoints[id] = RandomKeypoints(counts[id - 1]);
      descriptors[id] = RandomDescriptors(counts[id - 1]);
    }
  }

  void Write(const std::filesystem::path& path) const {
    DatabaseWriter writer(path);
    for (const Camera& camera : cameras) writer.WriteCamera(camera);
    for (const DatabaseImage& image : images) writer.WriteImage(image);
    for (const auto& [id, kps] : keypoints) writer.WriteKeypoints(id, kps);
    for (const auto& [id, desc] : descriptors) writer.WriteDescriptors(id, desc);
    writer.Commit();
  }

  // Checks everything a reader of `path` returns against this content.
  void ExpectReads(const DatabaseReader& reader) const {
    EXPECT_EQ(reader.ReadAllCameras(), cameras);
    EXPECT_EQ(reader.ReadAllImages(), images);
    for (const DatabaseImage& image : images) {
      const auto kp_it = keypoints.find(image.image_id);
      const auto desc_it = descriptors.find(image.image_id);
      const std::vector<Keypoint> expected_kps =
          kp_it == keypoints.end() ? std::vector<Keypoint>{} : kp_it->second;
      const Descriptors expected_desc =
          desc_it == descriptors.end() ? Descriptors{} : desc_it->second;
      EXPECT_EQ(reader.ReadKeypoints(image.image_id), expected_kps) << image.name;
      const Descriptors desc = reader.ReadDescriptors(image.image_id);
      EXPECT_EQ(desc.rows, expected_desc.rows) << image.name;
      EXPECT_EQ(desc.data, expected_desc.data) << image.name;
      EXPECT_EQ(reader.NumKeypoints(image.image_id), expected_kps.size());
      EXPECT_EQ(reader.NumDescriptors(image.image_id), expected_desc.rows);
      const ImageFeatures features = reader.ReadFeatures(image.image_id);
      EXPECT_EQ(features.keypoints.size(), features.descriptors.rows);
    }
  }
};

std::string ReadBytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::set<std::string> ListDir(const std::filesystem::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    names.insert(entry.path().filename().string());
  }
  return names;
}

using test::InputErrorOf;

TEST(DatabaseTest, RoundTrip) {
  test::TempDir dir;
  const SmallDatabase content;
  content.Write(dir / "database.db");
  EXPECT_EQ(ListDir(dir.path()), std::set<std::string>{"database.db"});

  const DatabaseReader reader(dir / "database.db");
  EXPECT_EQ(reader.user_version(), 3800);
  EXPECT_FALSE(reader.has_descriptor_type());
  content.ExpectReads(reader);
  EXPECT_EQ(reader.FindImage("sub/c.jpg"), (DatabaseImage{3, "sub/c.jpg", 2}));
  EXPECT_FALSE(reader.FindImage("missing.jpg").has_value());
  EXPECT_TRUE(reader.ReadKeypoints(99).empty());
  EXPECT_EQ(reader.ReadDescriptors(99).rows, 0u);
}

TEST(DatabaseTest, WriterUsesColmap38Schema) {
  test::TempDir dir;
  SmallDatabase().Write(dir / "database.db");
  RawDb db(dir / "database.db");
  EXPECT_EQ(db.QueryInt("PRAGMA user_version"), 3800);
  EXPECT_EQ(db.QueryStrings("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name"),
            (std::vector<std::string>{"cameras", "descriptors", "images", "keypoints", "matches",
                                      "sqlite_sequence", "two_view_geometries"}));
  EXPECT_EQ(db.QueryInt("SELECT count(*) FROM matches"), 0);
  EXPECT_EQ(db.QueryInt("SELECT count(*) FROM two_view_geometries"), 0);
  EXPECT_EQ(db.QueryInt("SELECT prior_focal_length FROM cameras WHERE camera_id = 1"), 0);
  EXPECT_EQ(db.QueryInt("SELECT cols FROM keypoints WHERE image_id = 1"), 6);
  // AUTOINCREMENT bookkeeping so that colmap appends new images after ours.
  EXPECT_EQ(db.QueryInt("SELECT seq FROM sqlite_sequence WHERE name = 'images'"), 4);
  // Not left in WAL mode: a read-only open never needs side files.
  EXPECT_EQ(db.QueryStrings("PRAGMA journal_mode"), std::vector<std::string>{"delete"});
}

std::string WithoutSpace(std::string s) {
  s.erase(std::remove_if(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c); }),
          s.end());
  return s;
}

TEST(DatabaseTest, WriterSchemaEqualsRealColmap38Database) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  test::TempDir dir;
  SmallDatabase().Write(dir / "database.db");
  const std::string kSchemaQuery =
      "SELECT type || ' ' || name || ' ' || ifnull(sql, '') FROM sqlite_master ORDER BY name";
  std::vector<std::string> ours = RawDb(dir / "database.db").QueryStrings(kSchemaQuery);
  // Read-only and immutable: the shared file must not be touched.
  const std::string uri = "file:" + (data / "database.db").string() + "?immutable=1";
  sqlite3* real = nullptr;
  ASSERT_EQ(sqlite3_open_v2(uri.c_str(), &real, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr),
            SQLITE_OK);
  std::vector<std::string> theirs;
  sqlite3_stmt* stmt = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(real, kSchemaQuery.c_str(), -1, &stmt, nullptr), SQLITE_OK);
  while (sqlite3_step(stmt) == SQLITE_ROW) {
    theirs.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0)));
  }
  sqlite3_finalize(stmt);
  sqlite3_close(real);
  std::transform(ours.begin(), ours.end(), ours.begin(), WithoutSpace);
  std::transform(theirs.begin(), theirs.end(), theirs.begin(), WithoutSpace);
  EXPECT_EQ(ours, theirs);
}

TEST(DatabaseTest, WriterWithoutCommitLeavesNothing) {
  test::TempDir dir;
  {
    DatabaseWriter writer(dir / "database.db");
    writer.WriteImage({1, "a.jpg", 1});
    writer.WriteDescriptors(1, RandomDescriptors(5));
    EXPECT_EQ(ListDir(dir.path()).size(), 1u);  // only the temporary file
    EXPECT_FALSE(std::filesystem::exists(dir / "database.db"));
  }
  EXPECT_TRUE(ListDir(dir.path()).empty());
}

TEST(DatabaseTest, CommitReplacesExistingFileAtomically) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  const std::string old_bytes = ReadBytes(path);
  // A stale journal of the old file must not be replayed onto the new one.
  std::ofstream(dir / "database.db-journal") << "stale";
  {
    DatabaseWriter writer(path);
    writer.WriteCamera({7, CameraModelId::kSimplePinhole, 10, 20, {5, 5, 10}});
    EXPECT_EQ(ReadBytes(path), old_bytes);  // untouched until Commit
    writer.Commit();
    EXPECT_THROW(writer.WriteImage({1, "x.jpg", 7}), std::logic_error);
  }
  EXPECT_EQ(ListDir(dir.path()), std::set<std::string>{"database.db"});
  const DatabaseReader reader(path);
  EXPECT_EQ(reader.ReadAllCameras(),
            (std::vector<Camera>{{7, CameraModelId::kSimplePinhole, 10, 20, {5, 5, 10}}}));
  EXPECT_TRUE(reader.ReadAllImages().empty());
}

TEST(DatabaseTest, WriterRejectsBadArguments) {
  test::TempDir dir;
  DatabaseWriter writer(dir / "database.db");
  EXPECT_THROW(writer.WriteCamera({1, CameraModelId::kPinhole, 10, 10, {1, 2, 3}}),
               std::invalid_argument);
  EXPECT_THROW(writer.WriteImage({2147483647u, "a.jpg", 1}), std::invalid_argument);
  Descriptors bad = RandomDescriptors(3);
  bad.data.pop_back();
  EXPECT_THROW(writer.WriteDescriptors(1, bad), std::invalid_argument);
  writer.WriteImage({1, "a.jpg", 1});
  EXPECT_THROW(writer.WriteImage({2, "a.jpg", 1}), std::runtime_error);  // UNIQUE name
}

TEST(DatabaseTest, ReadsTwoAndFourColumnKeypoints) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase content;
  content.Write(path);
  const std::vector<float> two = {1.5f, 2.5f, 3.5f, 4.5f};  // 2 rows x (x, y)
  const std::vector<float> four = {10, 20, 2.0f, 0.5f,
                                   30, 40, 0.0f, -1.0f};  // x, y, scale, orientation
  {
    RawDb db(path);
    db.ExecWithBlob("UPDATE keypoints SET rows = 2, cols = 2, data = ?1 WHERE image_id = 1",
                    two.data(), two.size() * sizeof(float));
    db.ExecWithBlob("UPDATE keypoints SET rows = 2, cols = 4, data = ?1 WHERE image_id = 2",
                    four.data(), four.size() * sizeof(float));
  }
  const DatabaseReader reader(path);
  EXPECT_EQ(reader.ReadKeypoints(1),
            (std::vector<Keypoint>{{1.5f, 2.5f, 1, 0, 0, 1}, {3.5f, 4.5f, 1, 0, 0, 1}}));
  const std::vector<Keypoint> kps = reader.ReadKeypoints(2);
  ASSERT_EQ(kps.size(), 2u);
  EXPECT_EQ(kps[0].x, 10);
  EXPECT_EQ(kps[0].y, 20);
  EXPECT_FLOAT_EQ(kps[0].a11, 2 * std::cos(0.5f));
  EXPECT_FLOAT_EQ(kps[0].a12, -2 * std::sin(0.5f));
  EXPECT_FLOAT_EQ(kps[0].a21, 2 * std::sin(0.5f));
  EXPECT_FLOAT_EQ(kps[0].a22, 2 * std::cos(0.5f));
  EXPECT_FLOAT_EQ(kps[0].Scale(), 2);
  EXPECT_FLOAT_EQ(kps[0].Orientation(), 0.5f);
  EXPECT_FLOAT_EQ(kps[1].Scale(), 0);
  EXPECT_EQ(reader.NumKeypoints(1), 2u);
  EXPECT_EQ(reader.NumKeypoints(2), 2u);
  EXPECT_EQ(reader.ReadKeypoints(3), content.keypoints.at(3));  // 6 columns still exact
}

// Everything observable about a database file and its directory.
struct FileSnapshot {
  std::string bytes;
  std::filesystem::file_time_type mtime;
  std::set<std::string> dir_entries;
  bool operator==(const FileSnapshot&) const = default;
};

FileSnapshot Snapshot(const std::filesystem::path& path) {
  return {ReadBytes(path), std::filesystem::last_write_time(path), ListDir(path.parent_path())};
}

TEST(DatabaseTest, ReaderNeverModifiesTheFile) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  content.Write(path);
  const FileSnapshot before = Snapshot(path);
  {
    const DatabaseReader reader(path);
    content.ExpectReads(reader);
    EXPECT_EQ(Snapshot(path), before);  // also while open: no -journal, -wal or -shm
  }
  EXPECT_EQ(Snapshot(path), before);
}

// colmap leaves its databases in WAL mode; a plain read-only open of such a file would
// create -wal and -shm files and leave them behind.
TEST(DatabaseTest, ReaderLeavesWalDatabaseUntouched) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  content.Write(path);
  RawDb(path).Exec("PRAGMA journal_mode = WAL");
  ASSERT_EQ(ListDir(dir.path()), std::set<std::string>{"database.db"});
  const FileSnapshot before = Snapshot(path);
  {
    const DatabaseReader reader(path);
    content.ExpectReads(reader);
  }
  EXPECT_EQ(Snapshot(path), before);
}

// While colmap (here: another connection) has the WAL database open, its newest commits
// live in the -wal file; the reader must see them and add no files.
TEST(DatabaseTest, ReaderSeesCommitsInALiveWriteAheadLog) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase content;
  content.Write(path);
  RawDb writer(path);
  writer.Exec("PRAGMA journal_mode = WAL");
  writer.Exec("INSERT INTO images(image_id, name, camera_id) VALUES(5, 'e.jpg', 1)");
  const std::set<std::string> entries = ListDir(dir.path());
  ASSERT_EQ(entries, (std::set<std::string>{"database.db", "database.db-shm", "database.db-wal"}));
  {
    const DatabaseReader reader(path);
    content.images.push_back({5, "e.jpg", 1});
    content.ExpectReads(reader);
  }
  EXPECT_EQ(ListDir(dir.path()), entries);
}

// A writer in an open transaction that has not touched the file yet: SQLite's shared lock
// gives the reader the last committed state.
TEST(DatabaseTest, ReadsCommittedStateDuringAnOpenTransaction) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  content.Write(path);
  RawDb writer(path);
  writer.Exec("BEGIN; DELETE FROM descriptors; UPDATE images SET name = 'x' || name;");
  ASSERT_TRUE(std::filesystem::exists(dir / "database.db-journal"));
  content.ExpectReads(DatabaseReader(path));
  writer.Exec("ROLLBACK");
}

// Once a writer has spilled pages into the file (or crashed mid-commit), the journal is
// live (it starts with its magic): refuse rather than read half-written pages.
TEST(DatabaseTest, RefusesDatabaseWithLiveJournal) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb writer(path);
  writer.Exec("PRAGMA cache_size = 2; BEGIN; UPDATE descriptors SET data = randomblob(100000);");
  ASSERT_TRUE(std::filesystem::exists(dir / "database.db-journal"));
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(path); }),
            path.string() + ": has a live rollback journal (" + path.string() +
                "-journal): another process is writing it or crashed while writing");
  writer.Exec("ROLLBACK");
}

TEST(DatabaseTest, MissingFile) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(path); }), path.string() + ": no such file");
  EXPECT_TRUE(ListDir(dir.path()).empty());  // nothing created
}

TEST(DatabaseTest, NotAnSqliteFile) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  std::ofstream(path) << "cameras.txt is not a database\n";
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(path); }),
            path.string() + ": not an SQLite database (COLMAP's database.db is SQLite 3)");
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(dir.path()); }),
            dir.path().string() + ": is a directory, expected a COLMAP database.db file");
}

TEST(DatabaseTest, MissingTableOrColumn) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb(path).Exec("DROP TABLE descriptors");
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(path); }),
            path.string() + ": not a COLMAP database: table 'descriptors' is missing");

  RawDb db(path);
  db.Exec(
      "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER, data BLOB)");
  EXPECT_EQ(InputErrorOf([&] { DatabaseReader reader(path); }),
            path.string() + ": not a COLMAP database: table 'descriptors' has no column 'cols'");
}

TEST(DatabaseTest, WrongDescriptorBlobSize) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb(path).Exec("UPDATE descriptors SET data = zeroblob(1000) WHERE image_id = 1");
  const DatabaseReader reader(path);
  const std::string expected = path.string() +
                               ": table 'descriptors', image 1 'a.jpg': data blob has 1000 bytes, "
                               "expected 1280 (10 rows x 128 cols x 1-byte uint8)";
  EXPECT_EQ(InputErrorOf([&] { reader.ReadDescriptors(1); }), expected);
  EXPECT_EQ(InputErrorOf([&] { reader.NumDescriptors(1); }), expected);
  EXPECT_EQ(InputErrorOf([&] { reader.ReadFeatures(1); }), expected);
  EXPECT_EQ(reader.ReadDescriptors(2).rows, 37u);  // other images still read
}

TEST(DatabaseTest, DescriptorColumnsMustBe128) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb(path).Exec("UPDATE descriptors SET cols = 64, data = zeroblob(37 * 64) WHERE image_id = 2");
  const DatabaseReader reader(path);
  const std::string expected =
      path.string() + ": table 'descriptors', image 2 'b.jpg': 64 columns per row, expected 128";
  EXPECT_EQ(InputErrorOf([&] { reader.ReadDescriptors(2); }), expected);
  EXPECT_EQ(InputErrorOf([&] { reader.NumDescriptors(2); }), expected);
}

TEST(DatabaseTest, BadKeypointRows) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  {
    RawDb db(path);
    db.Exec("UPDATE keypoints SET cols = 5, data = zeroblob(10 * 5 * 4) WHERE image_id = 1");
    db.Exec("UPDATE keypoints SET data = zeroblob(12) WHERE image_id = 2");
    db.Exec("UPDATE keypoints SET rows = 2, data = zeroblob(2 * 6 * 4) WHERE image_id = 3");
    db.Exec("INSERT INTO descriptors(image_id, rows, cols, data) VALUES(9, 0, 128, x'')");
    db.Exec("UPDATE descriptors SET data = 'text' WHERE image_id = 9");
  }
  const DatabaseReader reader(path);
  EXPECT_EQ(InputErrorOf([&] { reader.ReadKeypoints(1); }),
            path.string() +
                ": table 'keypoints', image 1 'a.jpg': 5 columns per row, expected 2, 4 or 6");
  EXPECT_EQ(InputErrorOf([&] { reader.ReadKeypoints(2); }),
            path.string() +
                ": table 'keypoints', image 2 'b.jpg': data blob has 12 bytes, expected " +
                "888 (37 rows x 6 cols x 4-byte float)");
  EXPECT_EQ(InputErrorOf([&] { reader.ReadFeatures(3); }),
            path.string() +
                ": image 3 'sub/c.jpg': table 'keypoints' has 2 rows but table "
                "'descriptors' has 1; they must match");
  EXPECT_EQ(InputErrorOf([&] { reader.ReadDescriptors(9); }),
            path.string() +
                ": table 'descriptors', image 9 (not in table 'images'): column 'data' "
                "is TEXT, expected a BLOB of 0 bytes");
}

TEST(DatabaseTest, UnknownCameraModel) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb(path).Exec("UPDATE cameras SET model = 99 WHERE camera_id = 2");
  const DatabaseReader reader(path);
  EXPECT_EQ(InputErrorOf([&] { reader.ReadAllCameras(); }),
            path.string() + ": table 'cameras', camera 2: unknown camera model id 99");
}

TEST(DatabaseTest, WrongCameraParamCount) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  SmallDatabase().Write(path);
  RawDb(path).Exec("UPDATE cameras SET params = zeroblob(24) WHERE camera_id = 1");
  const DatabaseReader reader(path);
  EXPECT_EQ(InputErrorOf([&] { reader.ReadAllCameras(); }),
            path.string() +
                ": table 'cameras', camera 1 (SIMPLE_RADIAL): params blob has 24 bytes, "
                "expected 32 bytes (4 doubles)");
}

// The schemas of newer COLMAP releases, from src/colmap/scene/database_sqlite.cc (written
// out here; only the tables the reader needs and the ones that changed).
enum class Schema { kColmap310, kColmap312, kColmap4 };

std::string NewerSchemaSql(Schema schema) {
  std::string sql =
      "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model INTEGER "
      "NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length "
      "INTEGER NOT NULL);"
      // No prior_* columns since 3.10.
      "CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT "
      "NULL UNIQUE, camera_id INTEGER NOT NULL, CONSTRAINT image_id_check CHECK(image_id >= 0 and "
      "image_id < 2147483647), FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));"
      "CREATE UNIQUE INDEX index_name ON images(name);"
      "CREATE TABLE keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols "
      "INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE "
      "CASCADE);"
      "CREATE TABLE matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols "
      "INTEGER NOT NULL, data BLOB);";
  if (schema == Schema::kColmap4) {
    // 4.0 tags descriptors with their FeatureExtractorType (SIFT = 0).
    sql +=
        "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, type INTEGER NOT NULL, "
        "rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) "
        "REFERENCES images(image_id) ON DELETE CASCADE);";
  } else {
    sql +=
        "CREATE TABLE descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, "
        "cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON "
        "DELETE CASCADE);";
  }
  if (schema == Schema::kColmap310) {
    sql +=
        "CREATE TABLE pose_priors (image_id INTEGER PRIMARY KEY NOT NULL, position BLOB, "
        "coordinate_system INTEGER NOT NULL, position_covariance BLOB, FOREIGN KEY(image_id) "
        "REFERENCES images(image_id) ON DELETE CASCADE);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER "
        "NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, "
        "H BLOB, qvec BLOB, tvec BLOB);"
        "PRAGMA user_version = 3900;";
    return sql;
  }
  sql +=
      "CREATE TABLE rigs (rig_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, ref_sensor_id INTEGER "
      "NOT NULL, ref_sensor_type INTEGER NOT NULL);"
      "CREATE UNIQUE INDEX rig_ref_sensor_assignment ON rigs(ref_sensor_id, ref_sensor_type);"
      "CREATE TABLE rig_sensors (rig_id INTEGER NOT NULL, sensor_id INTEGER NOT NULL, sensor_type "
      "INTEGER NOT NULL, sensor_from_rig BLOB, FOREIGN KEY(rig_id) REFERENCES rigs(rig_id) ON "
      "DELETE CASCADE);"
      "CREATE TABLE frames (frame_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, rig_id INTEGER "
      "NOT "
      "NULL, FOREIGN KEY(rig_id) REFERENCES rigs(rig_id) ON DELETE CASCADE);"
      "CREATE TABLE frame_data (frame_id INTEGER NOT NULL, data_id INTEGER NOT NULL, sensor_id "
      "INTEGER NOT NULL, sensor_type INTEGER NOT NULL, FOREIGN KEY(frame_id) REFERENCES "
      "frames(frame_id) ON DELETE CASCADE);"
      "CREATE UNIQUE INDEX frame_sensor_assignment ON frame_data(data_id, sensor_type);";
  if (schema == Schema::kColmap312) {
    sql +=
        "CREATE TABLE pose_priors (image_id INTEGER PRIMARY KEY NOT NULL, position BLOB, "
        "coordinate_system INTEGER NOT NULL, position_covariance BLOB, FOREIGN KEY(image_id) "
        "REFERENCES images(image_id) ON DELETE CASCADE);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER "
        "NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, "
        "H BLOB, qvec BLOB, tvec BLOB);"
        "PRAGMA user_version = 3900;";
  } else {
    sql +=
        "CREATE TABLE pose_priors (pose_prior_id INTEGER PRIMARY KEY NOT NULL, corr_data_id "
        "INTEGER NOT NULL, corr_sensor_id INTEGER NOT NULL, corr_sensor_type INTEGER NOT NULL, "
        "position BLOB, position_covariance BLOB, gravity BLOB, coordinate_system INTEGER NOT "
        "NULL);"
        "CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER "
        "NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, "
        "H BLOB, qvec BLOB, tvec BLOB, camera1 BLOB, camera2 BLOB);"
        "PRAGMA user_version = 4020000;";
  }
  return sql;
}

// Fills a database of a newer schema the way that COLMAP version does (WAL mode included).
void WriteNewerDatabase(const std::filesystem::path& path, Schema schema,
                        const SmallDatabase& content, int descriptor_type = 0) {
  RawDb db(path);
  db.Exec("PRAGMA journal_mode = WAL");
  db.Exec(NewerSchemaSql(schema));
  for (const Camera& camera : content.cameras) {
    db.ExecWithBlob("INSERT INTO cameras VALUES(" + std::to_string(camera.camera_id) + ", " +
                        std::to_string(static_cast<int>(camera.model_id)) + ", " +
                        std::to_string(camera.width) + ", " + std::to_string(camera.height) +
                        ", ?1, 1)",
                    camera.params.data(), camera.params.size() * sizeof(double));
  }
  for (const DatabaseImage& image : content.images) {
    db.Exec("INSERT INTO images VALUES(" + std::to_string(image.image_id) + ", '" + image.name +
            "', " + std::to_string(image.camera_id) + ")");
  }
  for (const auto& [id, kps] : content.keypoints) {
    std::vector<float> blob;
    for (const Keypoint& kp : kps)
      blob.insert(blob.end(), {kp.x, kp.y, kp.a11, kp.a12, kp.a21, kp.a22});
    db.ExecWithBlob("INSERT INTO keypoints VALUES(" + std::to_string(id) + ", " +
                        std::to_string(kps.size()) + ", 6, ?1)",
                    blob.data(), blob.size() * sizeof(float));
  }
  for (const auto& [id, desc] : content.descriptors) {
    const std::string type =
        schema == Schema::kColmap4 ? std::to_string(descriptor_type) + ", " : "";
    db.ExecWithBlob("INSERT INTO descriptors VALUES(" + std::to_string(id) + ", " + type +
                        std::to_string(desc.rows) + ", 128, ?1)",
                    desc.data.data(), desc.data.size());
  }
}

class DatabaseNewerSchemaTest : public testing::TestWithParam<Schema> {};

TEST_P(DatabaseNewerSchemaTest, Reads) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  WriteNewerDatabase(path, GetParam(), content);
  const FileSnapshot before = Snapshot(path);
  {
    const DatabaseReader reader(path);
    EXPECT_EQ(reader.has_descriptor_type(), GetParam() == Schema::kColmap4);
    EXPECT_EQ(reader.user_version(), GetParam() == Schema::kColmap4 ? 4020000 : 3900);
    content.ExpectReads(reader);
    // Written with prior_focal_length = 1.
    EXPECT_TRUE(reader.has_prior_focal_length());
    std::map<camera_t, bool> priors;
    for (const Camera& camera : content.cameras) priors[camera.camera_id] = true;
    EXPECT_EQ(reader.ReadPriorFocalLengths(), priors);
  }
  EXPECT_EQ(Snapshot(path), before);
}

INSTANTIATE_TEST_SUITE_P(Schemas, DatabaseNewerSchemaTest,
                         testing::Values(Schema::kColmap310, Schema::kColmap312, Schema::kColmap4),
                         [](const testing::TestParamInfo<Schema>& param_info) {
                           switch (param_info.param) {
                             case Schema::kColmap310:
                               return std::string("Colmap3_10");
                             case Schema::kColmap312:
                               return std::string("Colmap3_12");
                             default:
                               return std::string("Colmap4");
                           }
                         });

// COLMAP >= 4.0 migrates an older database by appending the type column (SIFT by default),
// so it comes last there rather than second.
TEST(DatabaseTest, ReadsDatabaseMigratedByColmap4) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  content.Write(path);
  RawDb(path).Exec(
      "ALTER TABLE descriptors ADD COLUMN type INTEGER NOT NULL DEFAULT 0;"
      "ALTER TABLE two_view_geometries ADD COLUMN camera1 BLOB;"
      "PRAGMA user_version = 4010100;");
  const DatabaseReader reader(path);
  EXPECT_TRUE(reader.has_descriptor_type());
  EXPECT_EQ(reader.user_version(), 4010100);
  content.ExpectReads(reader);
}

TEST(DatabaseTest, ReadsPriorFocalLengthFlags) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  const SmallDatabase content;
  content.Write(path);  // the writer stores prior_focal_length = 0
  {
    const DatabaseReader reader(path);
    EXPECT_TRUE(reader.has_prior_focal_length());
    std::map<camera_t, bool> priors;
    for (const Camera& camera : content.cameras) priors[camera.camera_id] = false;
    EXPECT_EQ(reader.ReadPriorFocalLengths(), priors);
  }
  RawDb(path).Exec("UPDATE cameras SET prior_focal_length = 1 WHERE camera_id = 2");
  {
    const DatabaseReader reader(path);
    EXPECT_TRUE(reader.ReadPriorFocalLengths().at(2));
    EXPECT_FALSE(reader.ReadPriorFocalLengths().at(1));
  }
  RawDb(path).Exec("UPDATE cameras SET prior_focal_length = 'yes' WHERE camera_id = 2");
  {
    const DatabaseReader reader(path);
    EXPECT_EQ(InputErrorOf([&] { reader.ReadPriorFocalLengths(); }),
              path.string() +
                  ": table 'cameras', camera 2: column 'prior_focal_length' is TEXT, expected "
                  "INTEGER");
  }
  // A layout without the column is still read; it just has no flags.
  RawDb(path).Exec("ALTER TABLE cameras DROP COLUMN prior_focal_length");
  const DatabaseReader reader(path);
  EXPECT_FALSE(reader.has_prior_focal_length());
  EXPECT_TRUE(reader.ReadPriorFocalLengths().empty());
  content.ExpectReads(reader);
}

TEST(DatabaseTest, RejectsNonSiftDescriptorType) {
  test::TempDir dir;
  const std::filesystem::path path = dir / "database.db";
  WriteNewerDatabase(path, Schema::kColmap4, SmallDatabase(), /*descriptor_type=*/1);
  const DatabaseReader reader(path);
  const std::string expected = path.string() +
                               ": table 'descriptors', image 2 'b.jpg': descriptor type 1 "
                               "(ALIKED_N16ROT); only SIFT (type 0) is supported";
  EXPECT_EQ(InputErrorOf([&] { reader.ReadDescriptors(2); }), expected);
  EXPECT_EQ(InputErrorOf([&] { reader.NumDescriptors(2); }), expected);
}

TEST(DatabaseTest, ReadsRealColmapDatabase) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  const std::filesystem::path path = data / "database.db";
  const FileSnapshot before = Snapshot(path);
  {
    const DatabaseReader reader(path);
    EXPECT_EQ(reader.user_version(), 3800);
    const std::vector<Camera> cameras = reader.ReadAllCameras();
    ASSERT_EQ(cameras.size(), 1u);
    EXPECT_EQ(cameras[0].model_id, CameraModelId::kSimpleRadial);
    EXPECT_EQ(cameras[0].width, 1536u);
    EXPECT_EQ(cameras[0].height, 1024u);
    // The database keeps colmap's initial guess (1.2 * max(width, height)); the refined
    // focal length lives in the model.
    EXPECT_EQ(cameras[0].params, (std::vector<double>{1.2 * 1536, 768, 512, 0}));
    EXPECT_EQ(reader.ReadPriorFocalLengths(), (std::map<camera_t, bool>{{1, false}}));

    const std::vector<DatabaseImage> images = reader.ReadAllImages();
    ASSERT_EQ(images.size(), 25u);
    uint32_t min_rows = UINT32_MAX, max_rows = 0;
    uint64_t total = 0;
    for (const DatabaseImage& image : images) {
      EXPECT_EQ(image.camera_id, cameras[0].camera_id);
      const ImageFeatures features = reader.ReadFeatures(image.image_id);  // checks rows match
      EXPECT_EQ(reader.NumDescriptors(image.image_id), features.descriptors.rows);
      EXPECT_EQ(reader.NumKeypoints(image.image_id), features.keypoints.size());
      min_rows = std::min(min_rows, features.descriptors.rows);
      max_rows = std::max(max_rows, features.descriptors.rows);
      total += features.descriptors.rows;
    }
    EXPECT_EQ(min_rows, 6975u);
    EXPECT_EQ(max_rows, 8585u);
    EXPECT_EQ(total, 192491u);
    EXPECT_EQ(reader.FindImage("0002.jpg")->name, "0002.jpg");
  }
  EXPECT_EQ(Snapshot(path), before);
}

}  // namespace
}  // namespace cwloc::colmap
