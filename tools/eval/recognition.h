#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "tools/eval/result_reader.h"

namespace cwloc::eval {

// Location recognition (paper, Table 3): a ranked model image is right for a query when it
// sees at least `min_shared` of the model 3D points the query sees under ground truth.
inline constexpr std::array<int, 4> kRecognitionRanks = {1, 2, 5, 10};

struct RecognitionTruth {
  int min_shared = 12;
  std::map<std::string, std::set<uint32_t>> right_images;  // per query name: model image ids
};

// The 3D points each query sees: cwloc-synth's queries_gt_points.txt ("NAME POINT3D_ID...").
std::map<std::string, std::vector<uint64_t>> ReadQueryPoints(const std::filesystem::path& path);

// The same from a COLMAP model that contains the queries (e.g. herz_jesu_p25's full_model):
// each named image's observed 3D points. Queries missing from the model see no point.
std::map<std::string, std::vector<uint64_t>> QueryPointsFromModel(
    const std::filesystem::path& model_dir, const std::vector<std::string>& names);

// Right images of every query, counted against the mapping model's tracks.
RecognitionTruth MakeRecognitionTruth(
    const std::filesystem::path& mapping_model_dir,
    const std::map<std::string, std::vector<uint64_t>>& query_points, int min_shared);

struct RecognitionScores {
  int queries = 0;                                   // ground-truth queries scored
  int with_right_image = 0;                          // queries some model image is right for
  std::array<int, kRecognitionRanks.size()> hits{};  // queries with a right image in the top k
};

// Scores the ranked images of each ground-truth query (queries without a result are misses).
RecognitionScores ScoreRecognition(const RunResults& run,
                                   const std::vector<std::string>& query_names,
                                   const RecognitionTruth& truth);

}  // namespace cwloc::eval
