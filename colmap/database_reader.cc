#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <span>
#include <string_view>

#include "base/bounded_file.h"
#include "base/error.h"
#include "colmap/database.h"
#include "colmap/sqlite_util.h"

namespace cwloc::colmap {

// Blobs hold the writer's native floats/doubles; COLMAP runs on little-endian hosts and so
// do we (x86-64, ARM64).
static_assert(std::endian::native == std::endian::little, "database blobs are little-endian");

std::vector<float> KeypointPositions(const std::vector<Keypoint>& keypoints) {
  std::vector<float> positions;
  positions.reserve(keypoints.size() * 2);
  for (const Keypoint& keypoint : keypoints) {
    positions.push_back(keypoint.x);
    positions.push_back(keypoint.y);
  }
  return positions;
}

float Keypoint::Scale() const {
  return (std::sqrt(a11 * a11 + a21 * a21) + std::sqrt(a12 * a12 + a22 * a22)) / 2.0f;
}

float Keypoint::Orientation() const { return std::atan2(a21, a11); }

namespace {

using internal::CheckSqlite;
using internal::Prepare;
using internal::StmtPtr;
using internal::StmtScope;

// COLMAP >= 4.0 FeatureExtractorType: UNDEFINED = -1, SIFT = 0, ALIKED_N16ROT = 1,
// ALIKED_N32 = 2.
constexpr int64_t kSiftDescriptorType = 0;

std::string_view DescriptorTypeName(int64_t type) {
  switch (type) {
    case -1:
      return "UNDEFINED";
    case 0:
      return "SIFT";
    case 1:
      return "ALIKED_N16ROT";
    case 2:
      return "ALIKED_N32";
    default:
      return "unknown";
  }
}

// Required columns per table. Everything else (prior_* of COLMAP <= 3.9, rigs, frames,
// pose_priors, matches of any version) is ignored.
struct TableSpec {
  const char* table;
  std::array<const char*, 5> columns;  // nullptr-terminated
};
constexpr std::array<TableSpec, 4> kRequiredTables = {{
    {"cameras", {"camera_id", "model", "width", "height", "params"}},
    {"images", {"image_id", "name", "camera_id", nullptr, nullptr}},
    {"keypoints", {"image_id", "rows", "cols", "data", nullptr}},
    {"descriptors", {"image_id", "rows", "cols", "data", nullptr}},
}};

// SQLite URI filenames treat '?', '#' and '%' specially: escape everything unusual.
std::string FileUri(const std::filesystem::path& path) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string uri = "file:";
  for (const unsigned char c : std::filesystem::absolute(path).string()) {
    const bool plain = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                       c == '/' || c == '-' || c == '_' || c == '.' || c == '~';
    if (plain) {
      uri += static_cast<char>(c);
    } else {
      uri += '%';
      uri += kHex[c >> 4];
      uri += kHex[c & 15];
    }
  }
  return uri;
}

std::filesystem::path WithSuffix(const std::filesystem::path& path, const char* suffix) {
  std::filesystem::path result = path;
  result += suffix;
  return result;
}

bool Exists(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::exists(path, ec);
}

const char* SqliteTypeName(int type) {
  switch (type) {
    case SQLITE_INTEGER:
      return "INTEGER";
    case SQLITE_FLOAT:
      return "REAL";
    case SQLITE_TEXT:
      return "TEXT";
    case SQLITE_BLOB:
      return "BLOB";
    default:
      return "NULL";
  }
}

int SqliteTypeFromName(std::string_view name) {
  if (name == "integer") return SQLITE_INTEGER;
  if (name == "real") return SQLITE_FLOAT;
  if (name == "text") return SQLITE_TEXT;
  if (name == "blob") return SQLITE_BLOB;
  return SQLITE_NULL;
}

}  // namespace

namespace internal {

// The layout of a rows/cols/data table: keypoints or descriptors.
struct MatrixTable {
  const char* name;
  std::span<const int64_t> accepted_cols;  // what a non-empty matrix may have
  size_t element_size;
  const char* element_name;
  bool has_type;  // descriptors carry their extractor type in COLMAP >= 4.0
};

// Shape of one rows/cols/data row, checked against the table's layout.
struct MatrixRow {
  int64_t rows = 0;
  int64_t cols = 0;
  int data_type = SQLITE_NULL;  // SQLITE_BLOB, SQLITE_NULL, ...
  int64_t bytes = 0;
  const void* blob = nullptr;  // the data, unless only sizes were read
};

}  // namespace internal

namespace {

using internal::MatrixRow;
using internal::MatrixTable;

constexpr int64_t kKeypointCols[] = {2, 4, 6};
constexpr int64_t kDescriptorCols[] = {kDescriptorDim};
constexpr MatrixTable kKeypointsTable{"keypoints", kKeypointCols, sizeof(float), "float", false};
constexpr MatrixTable kDescriptorsTable{"descriptors", kDescriptorCols, sizeof(uint8_t), "uint8",
                                        true};

}  // namespace

struct DatabaseReader::Statements {
  StmtPtr read_cameras;
  StmtPtr read_prior_focal_lengths;  // only with the column
  StmtPtr read_images;
  StmtPtr find_image;
  StmtPtr image_name;
  StmtPtr read_keypoints;
  StmtPtr size_keypoints;
  StmtPtr read_descriptors;
  StmtPtr size_descriptors;
};

namespace {

// The URI that opens the database at `path` read-only and leaves no side files, once it is a
// file with SQLite's header and no live journal; throws InputError naming what it is instead.
std::string ReadOnlyUri(const std::filesystem::path& path) {
  const std::string file = path.string();
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(status)) throw InputError(file + ": no such file");
  if (std::filesystem::is_directory(status)) {
    throw InputError(file + ": is a directory, expected a COLMAP database.db file");
  }
  // A device or a pipe would have SQLite read it; no size limit (kColmapDatabaseFile).
  CheckInputFile(path, kColmapDatabaseFile);

  // Check the header ourselves: an SQLite handle on a non-database fails late and vaguely,
  // and bytes 18/19 tell whether the file is in WAL mode.
  std::array<char, 100> header{};
  {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError(file + ": cannot open for reading");
    in.read(header.data(), header.size());
    if (in.gcount() != static_cast<std::streamsize>(header.size()) ||
        std::memcmp(header.data(), "SQLite format 3", 16) != 0) {
      throw InputError(file + ": not an SQLite database (COLMAP's database.db is SQLite 3)");
    }
  }
  const bool wal_mode = header[18] == 2 || header[19] == 2;

  // A plain read-only connection to a WAL database creates -wal and -shm files and leaves
  // them behind. Without a -wal file all content is in the main file, so "immutable" reads
  // it without locks or side files. With a live -wal (a writer is active or crashed) we must
  // read through it, which only works without side effects when its -shm exists too.
  std::string uri = FileUri(path);
  if (wal_mode) {
    if (!Exists(WithSuffix(path, "-wal"))) {
      uri += "?immutable=1";
    } else if (!Exists(WithSuffix(path, "-shm"))) {
      throw InputError(file + ": has a write-ahead log (" + file +
                       "-wal) but no -shm file: it was not closed cleanly. Open it once with "
                       "colmap or run sqlite3 on it to fold the log in, then retry");
    } else {
      uri += "?mode=ro";
    }
  } else {
    // A journal that starts with its magic is live (a writer is active or crashed): SQLite
    // would have to roll it back, which a read-only connection cannot do.
    static constexpr unsigned char kJournalMagic[8] = {0xd9, 0xd5, 0x05, 0xf9,
                                                       0x20, 0xa1, 0x63, 0xd7};
    std::array<char, 8> journal{};
    std::ifstream in(WithSuffix(path, "-journal"), std::ios::binary);
    if (in && in.read(journal.data(), journal.size()) &&
        std::memcmp(journal.data(), kJournalMagic, journal.size()) == 0) {
      throw InputError(file + ": has a live rollback journal (" + file +
                       "-journal): another process is writing it or crashed while writing");
    }
    uri += "?mode=ro";
  }
  return uri;
}

}  // namespace

DatabaseReader::DatabaseReader(const std::filesystem::path& path) : path_(path) {
  const std::string file = path_.string();
  const std::string uri = ReadOnlyUri(path_);
  const int flags = SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(uri.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string message = internal::SqliteErrorMessage(db_, rc, file + ": cannot open");
    sqlite3_close(db_);
    db_ = nullptr;
    throw InputError(message);
  }

  try {
    BeginReading(file);
    CheckTables(file);
    PrepareStatements(file);
  } catch (...) {
    stmts_.reset();
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

void DatabaseReader::BeginReading(const std::string& file) {
  CheckSqlite<InputError>(
      db_, sqlite3_exec(db_, "PRAGMA query_only = 1", nullptr, nullptr, nullptr), file);
  // One read transaction for the reader's life: every query sees the same snapshot, and takes
  // no shared lock of its own (gathering a city's 13,734 images ran 27,000 queries).
  CheckSqlite<InputError>(db_, sqlite3_exec(db_, "BEGIN", nullptr, nullptr, nullptr), file);
  StmtPtr stmt = Prepare<InputError>(db_, "PRAGMA user_version", file);
  if (CheckSqlite<InputError>(db_, sqlite3_step(stmt.get()), file) == SQLITE_ROW) {
    user_version_ = sqlite3_column_int(stmt.get(), 0);
  }
}

void DatabaseReader::CheckTables(const std::string& file) {
  StmtPtr columns_stmt = Prepare<InputError>(db_, "SELECT name FROM pragma_table_info(?1)", file);
  auto read_columns = [&](const char* table) {
    std::vector<std::string> columns;
    StmtScope scope(columns_stmt.get());
    sqlite3_bind_text(columns_stmt.get(), 1, table, -1, SQLITE_STATIC);
    while (CheckSqlite<InputError>(db_, sqlite3_step(columns_stmt.get()), file) == SQLITE_ROW) {
      columns.emplace_back(
          reinterpret_cast<const char*>(sqlite3_column_text(columns_stmt.get(), 0)));
    }
    return columns;
  };
  for (const TableSpec& spec : kRequiredTables) {
    const std::vector<std::string> columns = read_columns(spec.table);
    if (columns.empty()) {
      throw InputError(file + ": not a COLMAP database: table '" + spec.table + "' is missing");
    }
    for (const char* column : spec.columns) {
      if (column == nullptr) break;
      if (std::find(columns.begin(), columns.end(), column) == columns.end()) {
        throw InputError(file + ": not a COLMAP database: table '" + spec.table +
                         "' has no column '" + column + "'");
      }
    }
    if (std::string_view(spec.table) == "descriptors") {
      has_descriptor_type_ = std::find(columns.begin(), columns.end(), "type") != columns.end();
    }
    if (std::string_view(spec.table) == "cameras") {
      has_prior_focal_length_ =
          std::find(columns.begin(), columns.end(), "prior_focal_length") != columns.end();
    }
  }
}

void DatabaseReader::PrepareStatements(const std::string& file) {
  stmts_ = std::make_unique<Statements>();
  stmts_->read_cameras = Prepare<InputError>(
      db_, "SELECT camera_id, model, width, height, params FROM cameras ORDER BY camera_id", file);
  if (has_prior_focal_length_) {
    stmts_->read_prior_focal_lengths = Prepare<InputError>(
        db_, "SELECT camera_id, prior_focal_length FROM cameras ORDER BY camera_id", file);
  }
  stmts_->read_images = Prepare<InputError>(
      db_, "SELECT image_id, name, camera_id FROM images ORDER BY image_id", file);
  stmts_->find_image = Prepare<InputError>(
      db_, "SELECT image_id, name, camera_id FROM images WHERE name = ?1", file);
  stmts_->image_name =
      Prepare<InputError>(db_, "SELECT name FROM images WHERE image_id = ?1", file);
  stmts_->read_keypoints =
      Prepare<InputError>(db_, "SELECT rows, cols, data FROM keypoints WHERE image_id = ?1", file);
  // length() and typeof() of a blob column read the record header only, not the blob.
  stmts_->size_keypoints = Prepare<InputError>(
      db_, "SELECT rows, cols, length(data), typeof(data) FROM keypoints WHERE image_id = ?1",
      file);
  const std::string type_column = has_descriptor_type_ ? "type" : "0";
  stmts_->read_descriptors = Prepare<InputError>(
      db_, "SELECT rows, cols, data, " + type_column + " FROM descriptors WHERE image_id = ?1",
      file);
  stmts_->size_descriptors =
      Prepare<InputError>(db_,
                          "SELECT rows, cols, length(data), typeof(data), " + type_column +
                              " FROM descriptors WHERE image_id = ?1",
                          file);
}

DatabaseReader::~DatabaseReader() {
  stmts_.reset();  // statements must be finalized before the connection closes
  sqlite3_close(db_);
}

std::string DatabaseReader::ImageLabel(image_t image_id) const {
  std::string label = "image " + std::to_string(image_id);
  sqlite3_stmt* stmt = stmts_->image_name.get();
  StmtScope scope(stmt);
  sqlite3_bind_int64(stmt, 1, image_id);
  if (sqlite3_step(stmt) == SQLITE_ROW && sqlite3_column_type(stmt, 0) == SQLITE_TEXT) {
    label += " '";
    label += reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
    label += "'";
  } else {
    label += " (not in table 'images')";
  }
  return label;
}

namespace {

// Builds "<file>: table 't', image 3 'a.jpg'" only when an error needs it: the image name
// costs a query.
using Where = std::function<std::string()>;

// Reads an INTEGER column or throws naming it.
int64_t IntegerColumn(sqlite3_stmt* stmt, int col, const Where& where, const char* name) {
  const int type = sqlite3_column_type(stmt, col);
  if (type != SQLITE_INTEGER) {
    throw InputError(where() + ": column '" + name + "' is " + SqliteTypeName(type) +
                     ", expected INTEGER");
  }
  return sqlite3_column_int64(stmt, col);
}

// Checks one keypoints/descriptors row: the column count is accepted and the blob holds
// exactly rows * cols elements.
void CheckMatrixRow(const MatrixRow& row, const MatrixTable& table, const Where& where) {
  const std::span<const int64_t> accepted_cols = table.accepted_cols;
  const size_t element_size = table.element_size;
  if (row.rows < 0 || row.cols < 0) {
    throw InputError(where() + ": negative shape " + std::to_string(row.rows) + " x " +
                     std::to_string(row.cols));
  }
  const bool cols_ok =
      std::find(accepted_cols.begin(), accepted_cols.end(), row.cols) != accepted_cols.end() ||
      (row.rows == 0 && row.cols == 0);
  if (!cols_ok) {
    std::string accepted;
    size_t i = 0;
    for (const int64_t c : accepted_cols) {
      if (i > 0) accepted += (i + 1 == accepted_cols.size()) ? " or " : ", ";
      accepted += std::to_string(c);
      ++i;
    }
    throw InputError(where() + ": " + std::to_string(row.cols) + " columns per row, expected " +
                     accepted);
  }
  // The largest SQLite blob is below 2^31 bytes; anything that would overflow is a mismatch.
  if (row.rows > std::numeric_limits<uint32_t>::max()) {
    throw InputError(where() + ": " + std::to_string(row.rows) +
                     " rows is more than a blob can hold");
  }
  const int64_t expected = row.rows * row.cols * static_cast<int64_t>(element_size);
  const bool type_ok =
      row.data_type == SQLITE_BLOB || (row.data_type == SQLITE_NULL && expected == 0);
  if (!type_ok) {
    throw InputError(where() + ": column 'data' is " + SqliteTypeName(row.data_type) +
                     ", expected a BLOB of " + std::to_string(expected) + " bytes");
  }
  if (row.bytes != expected) {
    throw InputError(where() + ": data blob has " + std::to_string(row.bytes) +
                     " bytes, expected " + std::to_string(expected) + " (" +
                     std::to_string(row.rows) + " rows x " + std::to_string(row.cols) + " cols x " +
                     std::to_string(element_size) + "-byte " + table.element_name + ")");
  }
}

void CheckDescriptorType(sqlite3_stmt* stmt, int col, const Where& where) {
  const int64_t type = IntegerColumn(stmt, col, where, "type");
  if (type != kSiftDescriptorType) {
    throw InputError(where() + ": descriptor type " + std::to_string(type) + " (" +
                     std::string(DescriptorTypeName(type)) + "); only SIFT (type 0) is supported");
  }
}

}  // namespace

std::vector<Camera> DatabaseReader::ReadAllCameras() const {
  const std::string file = path_.string();
  sqlite3_stmt* stmt = stmts_->read_cameras.get();
  StmtScope scope(stmt);
  std::vector<Camera> cameras;
  while (CheckSqlite<InputError>(db_, sqlite3_step(stmt), file) == SQLITE_ROW) {
    const std::string table = file + ": table 'cameras'";
    const int64_t camera_id = IntegerColumn(
        stmt, 0, [&] { return table; }, "camera_id");
    if (camera_id < 0 || camera_id >= std::numeric_limits<camera_t>::max()) {
      throw InputError(table + ": camera_id " + std::to_string(camera_id) + " out of range");
    }
    const std::string where = table + ", camera " + std::to_string(camera_id);
    const Where at = [&] { return where; };
    const int64_t model_id = IntegerColumn(stmt, 1, at, "model");
    const int64_t width = IntegerColumn(stmt, 2, at, "width");
    const int64_t height = IntegerColumn(stmt, 3, at, "height");
    const auto model = (model_id >= std::numeric_limits<int32_t>::min() &&
                        model_id <= std::numeric_limits<int32_t>::max())
                           ? FindCameraModel(static_cast<int32_t>(model_id))
                           : std::nullopt;
    if (!model) throw InputError(where + ": unknown camera model id " + std::to_string(model_id));
    if (width < 0 || height < 0) {
      throw InputError(where + ": negative size " + std::to_string(width) + " x " +
                       std::to_string(height));
    }
    const int params_type = sqlite3_column_type(stmt, 4);
    const size_t expected = static_cast<size_t>(model->num_params) * sizeof(double);
    const size_t bytes =
        params_type == SQLITE_BLOB ? static_cast<size_t>(sqlite3_column_bytes(stmt, 4)) : 0;
    if (params_type != SQLITE_BLOB || bytes != expected) {
      throw InputError(where + " (" + std::string(model->name) + "): params " +
                       (params_type == SQLITE_BLOB
                            ? "blob has " + std::to_string(bytes) + " bytes"
                            : std::string("is ") + SqliteTypeName(params_type)) +
                       ", expected " + std::to_string(expected) + " bytes (" +
                       std::to_string(model->num_params) + " doubles)");
    }
    Camera camera;
    camera.camera_id = static_cast<camera_t>(camera_id);
    camera.model_id = model->id;
    camera.width = static_cast<uint64_t>(width);
    camera.height = static_cast<uint64_t>(height);
    camera.params.resize(static_cast<size_t>(model->num_params));
    std::memcpy(camera.params.data(), sqlite3_column_blob(stmt, 4), expected);
    cameras.push_back(std::move(camera));
  }
  return cameras;
}

std::map<camera_t, bool> DatabaseReader::ReadPriorFocalLengths() const {
  std::map<camera_t, bool> priors;
  if (!has_prior_focal_length_) return priors;
  const std::string file = path_.string();
  sqlite3_stmt* stmt = stmts_->read_prior_focal_lengths.get();
  StmtScope scope(stmt);
  while (CheckSqlite<InputError>(db_, sqlite3_step(stmt), file) == SQLITE_ROW) {
    const std::string table = file + ": table 'cameras'";
    const int64_t camera_id = IntegerColumn(
        stmt, 0, [&] { return table; }, "camera_id");
    if (camera_id < 0 || camera_id >= std::numeric_limits<camera_t>::max()) {
      throw InputError(table + ": camera_id " + std::to_string(camera_id) + " out of range");
    }
    const std::string where = table + ", camera " + std::to_string(camera_id);
    // COLMAP reads the flag as an integer != 0.
    priors[static_cast<camera_t>(camera_id)] =
        IntegerColumn(
            stmt, 1, [&] { return where; }, "prior_focal_length") != 0;
  }
  return priors;
}

namespace {

DatabaseImage ReadImageRow(sqlite3_stmt* stmt, const std::string& file) {
  const std::string table = file + ": table 'images'";
  const int64_t image_id = IntegerColumn(
      stmt, 0, [&] { return table; }, "image_id");
  // COLMAP's own CHECK constraint: 0 <= image_id < 2^31 - 1.
  if (image_id < 0 || image_id >= std::numeric_limits<int32_t>::max()) {
    throw InputError(table + ": image_id " + std::to_string(image_id) + " out of range");
  }
  const std::string where = table + ", image " + std::to_string(image_id);
  if (sqlite3_column_type(stmt, 1) != SQLITE_TEXT) {
    throw InputError(where + ": column 'name' is " + SqliteTypeName(sqlite3_column_type(stmt, 1)) +
                     ", expected TEXT");
  }
  const int64_t camera_id = IntegerColumn(
      stmt, 2, [&] { return where; }, "camera_id");
  if (camera_id < 0 || camera_id >= std::numeric_limits<camera_t>::max()) {
    throw InputError(where + ": camera_id " + std::to_string(camera_id) + " out of range");
  }
  DatabaseImage image;
  image.image_id = static_cast<image_t>(image_id);
  image.name.assign(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 1)),
                    static_cast<size_t>(sqlite3_column_bytes(stmt, 1)));
  image.camera_id = static_cast<camera_t>(camera_id);
  return image;
}

}  // namespace

std::vector<DatabaseImage> DatabaseReader::ReadAllImages() const {
  const std::string file = path_.string();
  sqlite3_stmt* stmt = stmts_->read_images.get();
  StmtScope scope(stmt);
  std::vector<DatabaseImage> images;
  while (CheckSqlite<InputError>(db_, sqlite3_step(stmt), file) == SQLITE_ROW) {
    images.push_back(ReadImageRow(stmt, file));
  }
  return images;
}

std::optional<DatabaseImage> DatabaseReader::FindImage(const std::string& name) const {
  const std::string file = path_.string();
  sqlite3_stmt* stmt = stmts_->find_image.get();
  StmtScope scope(stmt);
  sqlite3_bind_text(stmt, 1, name.data(), static_cast<int>(name.size()), SQLITE_STATIC);
  if (CheckSqlite<InputError>(db_, sqlite3_step(stmt), file) != SQLITE_ROW) return std::nullopt;
  return ReadImageRow(stmt, file);
}

bool DatabaseReader::ReadMatrixRow(sqlite3_stmt* stmt, image_t image_id, const MatrixTable& table,
                                   bool sizes_only, MatrixRow* row) const {
  const std::string file = path_.string();
  sqlite3_bind_int64(stmt, 1, image_id);
  if (CheckSqlite<InputError>(db_, sqlite3_step(stmt), file) != SQLITE_ROW) return false;
  const Where where = [&] {
    return file + ": table '" + table.name + "', " + ImageLabel(image_id);
  };
  // Columns: rows, cols, then data or length(data) and typeof(data), then the type if any.
  row->rows = IntegerColumn(stmt, 0, where, "rows");
  row->cols = IntegerColumn(stmt, 1, where, "cols");
  if (table.has_type && has_descriptor_type_) CheckDescriptorType(stmt, sizes_only ? 4 : 3, where);
  if (sizes_only) {
    row->data_type =
        SqliteTypeFromName(reinterpret_cast<const char*>(sqlite3_column_text(stmt, 3)));
    row->bytes = sqlite3_column_int64(stmt, 2);
  } else {
    row->data_type = sqlite3_column_type(stmt, 2);
    row->blob = sqlite3_column_blob(stmt, 2);  // before _bytes, as SQLite advises
    row->bytes = sqlite3_column_bytes(stmt, 2);
    if (row->data_type != SQLITE_BLOB) row->blob = nullptr;
  }
  CheckMatrixRow(*row, table, where);
  return true;
}

std::vector<Keypoint> DatabaseReader::ReadKeypoints(image_t image_id) const {
  sqlite3_stmt* stmt = stmts_->read_keypoints.get();
  StmtScope scope(stmt);
  MatrixRow row;
  if (!ReadMatrixRow(stmt, image_id, kKeypointsTable, /*sizes_only=*/false, &row)) return {};

  const size_t rows = static_cast<size_t>(row.rows);
  const size_t cols = static_cast<size_t>(row.cols);
  std::vector<float> values(rows * cols);
  if (!values.empty()) std::memcpy(values.data(), row.blob, values.size() * sizeof(float));
  std::vector<Keypoint> keypoints(rows);
  for (size_t i = 0; i < rows; ++i) {
    const float* v = values.data() + i * cols;
    bool finite = true;
    for (size_t c = 0; c < cols; ++c) finite = finite && std::isfinite(v[c]);
    Keypoint& kp = keypoints[i];
    kp.x = v[0];
    kp.y = v[1];
    if (cols == 4) {
      // x, y, scale, orientation: the similarity COLMAP's FeatureKeypoint derives.
      if (v[2] < 0) finite = false;
      const float scale_cos = v[2] * std::cos(v[3]);
      const float scale_sin = v[2] * std::sin(v[3]);
      kp.a11 = scale_cos;
      kp.a12 = -scale_sin;
      kp.a21 = scale_sin;
      kp.a22 = scale_cos;
    } else if (cols == 6) {
      kp.a11 = v[2];
      kp.a12 = v[3];
      kp.a21 = v[4];
      kp.a22 = v[5];
    }
    if (!finite) {
      throw InputError(path_.string() + ": table 'keypoints', " + ImageLabel(image_id) +
                       ": keypoint " + std::to_string(i) +
                       " has a non-finite value or a negative scale");
    }
  }
  return keypoints;
}

Descriptors DatabaseReader::ReadDescriptors(image_t image_id) const {
  sqlite3_stmt* stmt = stmts_->read_descriptors.get();
  StmtScope scope(stmt);
  MatrixRow row;
  if (!ReadMatrixRow(stmt, image_id, kDescriptorsTable, /*sizes_only=*/false, &row)) return {};
  Descriptors descriptors;
  descriptors.rows = static_cast<uint32_t>(row.rows);
  descriptors.data.resize(size_t{descriptors.rows} * kDescriptorDim);
  if (!descriptors.data.empty()) {
    std::memcpy(descriptors.data.data(), row.blob, descriptors.data.size());
  }
  return descriptors;
}

ImageFeatures DatabaseReader::ReadFeatures(image_t image_id) const {
  ImageFeatures features;
  features.keypoints = ReadKeypoints(image_id);
  features.descriptors = ReadDescriptors(image_id);
  if (features.keypoints.size() != features.descriptors.rows) {
    throw InputError(path_.string() + ": " + ImageLabel(image_id) + ": table 'keypoints' has " +
                     std::to_string(features.keypoints.size()) +
                     " rows but table 'descriptors' has " +
                     std::to_string(features.descriptors.rows) + "; they must match");
  }
  return features;
}

uint32_t DatabaseReader::NumKeypoints(image_t image_id) const {
  sqlite3_stmt* stmt = stmts_->size_keypoints.get();
  StmtScope scope(stmt);
  MatrixRow row;
  const bool found = ReadMatrixRow(stmt, image_id, kKeypointsTable, /*sizes_only=*/true, &row);
  return found ? static_cast<uint32_t>(row.rows) : 0;
}

uint32_t DatabaseReader::NumDescriptors(image_t image_id) const {
  sqlite3_stmt* stmt = stmts_->size_descriptors.get();
  StmtScope scope(stmt);
  MatrixRow row;
  const bool found = ReadMatrixRow(stmt, image_id, kDescriptorsTable, /*sizes_only=*/true, &row);
  return found ? static_cast<uint32_t>(row.rows) : 0;
}

}  // namespace cwloc::colmap
