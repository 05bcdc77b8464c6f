#include <cstring>
#include <limits>
#include <stdexcept>
#include <system_error>

#include "colmap/database.h"
#include "colmap/sqlite_util.h"

namespace cwloc::colmap {
namespace {

using internal::CheckSqlite;
using internal::Prepare;
using internal::StmtPtr;
using internal::StmtScope;

// COLMAP 3.8's tables, in the order it creates them, token for token (only the white space
// differs from what its Database::CreateTables writes into sqlite_master). The statements
// stay plain CREATE TABLE: this file is new, and colmap's own CREATE ... IF NOT EXISTS then
// finds everything in place.
constexpr const char* kCreateTables =
    "CREATE TABLE cameras ("
    "camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, "
    "model INTEGER NOT NULL, "
    "width INTEGER NOT NULL, "
    "height INTEGER NOT NULL, "
    "params BLOB, "
    "prior_focal_length INTEGER NOT NULL);"
    "CREATE TABLE images ("
    "image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, "
    "name TEXT NOT NULL UNIQUE, "
    "camera_id INTEGER NOT NULL, "
    "prior_qw REAL, prior_qx REAL, prior_qy REAL, prior_qz REAL, "
    "prior_tx REAL, prior_ty REAL, prior_tz REAL,"
    "CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647),"
    "FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));"
    "CREATE UNIQUE INDEX index_name ON images(name);"
    "CREATE TABLE keypoints ("
    "image_id INTEGER PRIMARY KEY NOT NULL, "
    "rows INTEGER NOT NULL, "
    "cols INTEGER NOT NULL, "
    "data BLOB,"
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);"
    "CREATE TABLE descriptors ("
    "image_id INTEGER PRIMARY KEY NOT NULL, "
    "rows INTEGER NOT NULL, "
    "cols INTEGER NOT NULL, "
    "data BLOB,"
    "FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);"
    "CREATE TABLE matches ("
    "pair_id INTEGER PRIMARY KEY NOT NULL, "
    "rows INTEGER NOT NULL, "
    "cols INTEGER NOT NULL, "
    "data BLOB);"
    "CREATE TABLE two_view_geometries ("
    "pair_id INTEGER PRIMARY KEY NOT NULL, "
    "rows INTEGER NOT NULL, "
    "cols INTEGER NOT NULL, "
    "data BLOB, "
    "config INTEGER NOT NULL, "
    "F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);"
    // COLMAP_VERSION_NUMBER of 3.8; colmap >= 3.9 migrates from it.
    "PRAGMA user_version = 3800;";

// COLMAP's kMaxNumImages: image ids must stay below it (the images table CHECKs it).
constexpr int64_t kMaxImageId = std::numeric_limits<int32_t>::max();
constexpr int kWrittenKeypointCols = 6;

}  // namespace

struct DatabaseWriter::Statements {
  StmtPtr write_camera;
  StmtPtr write_image;
  StmtPtr write_keypoints;
  StmtPtr write_descriptors;
  std::vector<float> keypoint_buffer;  // reused so that writing does not allocate per image
};

DatabaseWriter::DatabaseWriter(const std::filesystem::path& path)
    : file_(path, AtomicFile::Temporary::kNamed) {
  const std::string file = path.string();
  const std::filesystem::path& temp_path = file_.temp_path();
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(temp_path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message =
        internal::SqliteErrorMessage(db_, rc, file + ": cannot open " + temp_path.string());
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error(message);
  }
  try {
    // Atomicity comes from the rename in Commit(), so the temporary file needs neither a
    // journal nor syncs: a crash leaves only a temp file behind.
    CheckSqlite(db_,
                sqlite3_exec(db_,
                             "PRAGMA journal_mode = OFF; PRAGMA synchronous = OFF; "
                             "PRAGMA locking_mode = EXCLUSIVE; PRAGMA temp_store = MEMORY;",
                             nullptr, nullptr, nullptr),
                file + ": setting up " + temp_path.string());
    CheckSqlite(db_, sqlite3_exec(db_, kCreateTables, nullptr, nullptr, nullptr),
                file + ": creating tables");
    CheckSqlite(db_, sqlite3_exec(db_, "BEGIN", nullptr, nullptr, nullptr), file);
    stmts_ = std::make_unique<Statements>();
    stmts_->write_camera = Prepare(db_,
                                   "INSERT INTO cameras(camera_id, model, width, height, params, "
                                   "prior_focal_length) VALUES(?1, ?2, ?3, ?4, ?5, 0)",
                                   file);
    stmts_->write_image =
        Prepare(db_, "INSERT INTO images(image_id, name, camera_id) VALUES(?1, ?2, ?3)", file);
    stmts_->write_keypoints = Prepare(
        db_, "INSERT INTO keypoints(image_id, rows, cols, data) VALUES(?1, ?2, ?3, ?4)", file);
    stmts_->write_descriptors = Prepare(
        db_, "INSERT INTO descriptors(image_id, rows, cols, data) VALUES(?1, ?2, ?3, ?4)", file);
  } catch (...) {
    Close();
    throw;
  }
}

void DatabaseWriter::Close() noexcept {
  stmts_.reset();
  sqlite3_close(db_);
  db_ = nullptr;
}

// Closes SQLite first; file_ then removes the temporary file unless Commit() published it.
DatabaseWriter::~DatabaseWriter() { Close(); }

namespace {

void CheckOpen(sqlite3* db, const std::filesystem::path& path) {
  if (db == nullptr) {
    throw std::logic_error(path.string() + ": DatabaseWriter used after Commit()");
  }
}

// Binds rows, cols and the blob (an empty blob rather than NULL for no rows, as COLMAP).
void BindMatrix(sqlite3* db, sqlite3_stmt* stmt, int64_t rows, int64_t cols, const void* data,
                size_t bytes, const std::string& what) {
  CheckSqlite(db, sqlite3_bind_int64(stmt, 2, rows), what);
  CheckSqlite(db, sqlite3_bind_int64(stmt, 3, cols), what);
  if (bytes == 0) {
    CheckSqlite(db, sqlite3_bind_zeroblob(stmt, 4, 0), what);
  } else {
    CheckSqlite(db, sqlite3_bind_blob64(stmt, 4, data, bytes, SQLITE_STATIC), what);
  }
}

}  // namespace

void DatabaseWriter::WriteCamera(const Camera& camera) {
  CheckOpen(db_, path());
  const std::string what = path().string() + ": camera " + std::to_string(camera.camera_id);
  const auto model = FindCameraModel(static_cast<int32_t>(camera.model_id));
  if (!model) {
    throw std::invalid_argument(what + ": unknown camera model id " +
                                std::to_string(static_cast<int32_t>(camera.model_id)));
  }
  if (camera.params.size() != static_cast<size_t>(model->num_params)) {
    throw std::invalid_argument(what + ": " + std::string(model->name) + " takes " +
                                std::to_string(model->num_params) + " params, got " +
                                std::to_string(camera.params.size()));
  }
  constexpr uint64_t kMaxSize = std::numeric_limits<int64_t>::max();
  if (camera.width > kMaxSize || camera.height > kMaxSize) {
    throw std::invalid_argument(what + ": size out of range");
  }
  sqlite3_stmt* stmt = stmts_->write_camera.get();
  StmtScope scope(stmt);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 1, camera.camera_id), what);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 2, static_cast<int32_t>(camera.model_id)), what);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 3, static_cast<int64_t>(camera.width)), what);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 4, static_cast<int64_t>(camera.height)), what);
  CheckSqlite(db_,
              sqlite3_bind_blob64(stmt, 5, camera.params.data(),
                                  camera.params.size() * sizeof(double), SQLITE_STATIC),
              what);
  CheckSqlite(db_, sqlite3_step(stmt), what);
}

void DatabaseWriter::WriteImage(const DatabaseImage& image) {
  CheckOpen(db_, path());
  const std::string what =
      path().string() + ": image " + std::to_string(image.image_id) + " '" + image.name + "'";
  if (image.image_id >= kMaxImageId) {
    throw std::invalid_argument(what + ": COLMAP image ids must be below 2147483647");
  }
  sqlite3_stmt* stmt = stmts_->write_image.get();
  StmtScope scope(stmt);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 1, image.image_id), what);
  CheckSqlite(db_,
              sqlite3_bind_text64(stmt, 2, image.name.data(), image.name.size(), SQLITE_STATIC,
                                  SQLITE_UTF8),
              what);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 3, image.camera_id), what);
  CheckSqlite(db_, sqlite3_step(stmt), what);
}

void DatabaseWriter::WriteKeypoints(image_t image_id, const std::vector<Keypoint>& keypoints) {
  CheckOpen(db_, path());
  const std::string what = path().string() + ": keypoints of image " + std::to_string(image_id);
  std::vector<float>& buffer = stmts_->keypoint_buffer;
  buffer.resize(keypoints.size() * kWrittenKeypointCols);
  float* out = buffer.data();
  for (const Keypoint& kp : keypoints) {
    *out++ = kp.x;
    *out++ = kp.y;
    *out++ = kp.a11;
    *out++ = kp.a12;
    *out++ = kp.a21;
    *out++ = kp.a22;
  }
  sqlite3_stmt* stmt = stmts_->write_keypoints.get();
  StmtScope scope(stmt);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 1, image_id), what);
  BindMatrix(db_, stmt, static_cast<int64_t>(keypoints.size()), kWrittenKeypointCols, buffer.data(),
             buffer.size() * sizeof(float), what);
  CheckSqlite(db_, sqlite3_step(stmt), what);
}

void DatabaseWriter::WriteDescriptors(image_t image_id, const Descriptors& descriptors) {
  CheckOpen(db_, path());
  const std::string what = path().string() + ": descriptors of image " + std::to_string(image_id);
  if (descriptors.data.size() != size_t{descriptors.rows} * kDescriptorDim) {
    throw std::invalid_argument(what + ": " + std::to_string(descriptors.rows) + " rows need " +
                                std::to_string(size_t{descriptors.rows} * kDescriptorDim) +
                                " bytes, got " + std::to_string(descriptors.data.size()));
  }
  sqlite3_stmt* stmt = stmts_->write_descriptors.get();
  StmtScope scope(stmt);
  CheckSqlite(db_, sqlite3_bind_int64(stmt, 1, image_id), what);
  BindMatrix(db_, stmt, descriptors.rows, kDescriptorDim, descriptors.data.data(),
             descriptors.data.size(), what);
  CheckSqlite(db_, sqlite3_step(stmt), what);
}

void DatabaseWriter::Commit() {
  CheckOpen(db_, path());
  const std::string file = path().string();
  CheckSqlite(db_, sqlite3_exec(db_, "COMMIT", nullptr, nullptr, nullptr), file + ": commit");
  stmts_.reset();
  const int rc = sqlite3_close(db_);
  if (rc != SQLITE_OK) {
    throw std::runtime_error(internal::SqliteErrorMessage(db_, rc, file + ": close"));
  }
  db_ = nullptr;

  // Side files of a database we replace belong to the old content: SQLite would replay a
  // stale -journal or -wal onto the new file.
  std::error_code ec;
  for (const char* suffix : {"-journal", "-wal", "-shm"}) {
    std::filesystem::path side = path();
    side += suffix;
    std::filesystem::remove(side, ec);
  }
  file_.Commit();
}

}  // namespace cwloc::colmap
