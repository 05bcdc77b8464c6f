#pragma once

// How cwloc-localize and libcwloc turn their inputs into a Query: where its features come
// from, which camera it gets and which priors, by the same rules (docs/cli.md).

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <unordered_map>

#include "app/option_table.h"
#include "app/query_priors.h"
#include "localizer/query.h"

namespace cwloc {

// One query to run.
struct QuerySource {
  enum class Kind {
    kDatabase,      // an image name in a COLMAP database (read by the CLI's database input)
    kTextFeatures,  // a COLMAP text feature file
    kPhoto,         // a JPEG or PNG file
    kFeatures,      // features in memory (the API)
    kImage,         // a photo in memory or a grey image (the API): the query has its size
  };
  std::string name;
  Kind kind = Kind::kDatabase;
  std::filesystem::path path{};  // the feature file or photo
  std::string camera_spec{};     // "MODEL W H PARAMS" from a list line, if any
  std::string list{};            // the list file that line came from

  // How errors name it: its file, or its name in the database.
  std::string Label() const;
};

// What a run says about every query's camera; each may be unset.
struct CameraInputs {
  std::optional<QueryCamera> camera;      // --camera; the API's Camera argument
  double focal_px = 0;                    // --focal: a prior (> 0)
  std::optional<QueryCamera> image_size;  // --image-size: only the size
  bool unknown_focal = false;             // --unknown-focal: withhold a known focal length
};

// What a run says about every query's priors.
struct PriorInputs {
  std::optional<PositionPrior> position;                   // --prior-position
  std::optional<std::array<double, 3>> gravity;            // --prior-gravity
  std::unordered_map<std::string, QueryPriors> per_query;  // --priors, by query name
};

class QueryAssembler {
 public:
  QueryAssembler(const QueryOptions& options, CameraInputs cameras, PriorInputs priors);

  // Reads a feature file's or a photo's features (kTextFeatures, kPhoto).
  Query Read(const QuerySource& source) const;

  // Gives a read query its camera and priors. The camera: a list line's, then --camera, then
  // --focal, then --image-size, then the query's own (a photo's EXIF or size, the database's);
  // a photo's camera must have its size. The priors: the --priors line's, then --prior-*, then
  // a photo's EXIF GPS when use_exif_gps is set. Throws InputError naming the query.
  void Complete(const QuerySource& source, Query* query) const;

 private:
  QueryCamera ChooseCamera(const QuerySource& source, const Query& query) const;
  void AddPriors(Query* query) const;

  const QueryOptions& options_;
  CameraInputs cameras_;
  PriorInputs priors_;
};

}  // namespace cwloc
