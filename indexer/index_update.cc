#include "indexer/index_update.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <map>

#include "base/parallel_for.h"
#include "base/stopwatch.h"
#include "colmap/database.h"
#include "cwloc/version.h"
#include "delta/apply_delta.h"
#include "delta/covisibility.h"
#include "delta/make_delta.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "indexer/build_option_table.h"
#include "indexer/clustering.h"
#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"
#include "indexer/model_views.h"
#include "indexer/neighbor_distances.h"
#include "indexer/point_codes.h"
#include "indexer/update_correspondence.h"
#include "kdtree/kd_forest_update.h"

namespace cwloc {
namespace {

// The build options an index was built with, as its manifest records them.
struct ParentBuild {
  IndexBuildOptions options;
  IndexBuildFlags flags;
  bool georeferenced = false;
};

ParentBuild ParentBuildOf(const nlohmann::ordered_json& manifest) {
  ParentBuild parent;
  const auto& build = manifest.at("build_parameters");
  parent.options.forest.num_trees = build.at("kd_trees").get<uint32_t>();
  parent.options.forest.max_leaf_size = build.at("kd_leaf_size").get<uint32_t>();
  parent.options.seed = build.at("seed").get<uint64_t>();
  parent.options.keypoints = build.at("keypoints").get<bool>();
  parent.options.point_colors = build.value("point_colors", false);
  if (build.contains("descriptors")) {
    parent.options.code_bytes = build["descriptors"].at("code_bytes").get<uint32_t>();
    parent.flags.compact = true;
  }
  const auto& clustering = build.at("clustering");
  const std::string method = clustering.at("method").get<std::string>();
  if (method == "file") {
    parent.flags.cluster_file = clustering.at("file").get<std::string>();
    parent.options.clustering.method = ClusteringMethod::kFile;
    parent.options.clustering.file = parent.flags.cluster_file;
  } else if (method == "covisibility") {
    parent.flags.clusters = clustering.at("target_clusters").get<uint32_t>();
    parent.options.clustering.method = ClusteringMethod::kCovisibility;
    parent.options.clustering.target_clusters = *parent.flags.clusters;
  }
  parent.georeferenced = manifest.contains("georeference") && manifest["georeference"].is_object();
  // The calibration's sample count as it ran (at most the option's); none without PCAL.
  parent.options.calibration_samples =
      manifest.contains("covariance_calibration")
          ? manifest["covariance_calibration"].value("sampled_images", uint32_t{0})
          : 0;
  return parent;
}

// Build flags an update cannot honour without a build: the georeference and the covariance
// calibration are kept from the parent.
bool KeptFromParent(std::string_view flag) {
  return flag == "georef" || flag == "georef-images" || flag == "model-frame" ||
         flag == "georef-sigma" || flag == "calibration-samples";
}

void CheckBuildFlags(const IndexUpdateOptions& options, const ParentBuild& parent) {
  for (const auto& [flag, value] : options.build_flags) {
    if (flag == "threads") continue;
    const BuildOptionSpec& spec = FindBuildOption(flag);
    if (KeptFromParent(flag)) {
      throw UpdateRefused(options.index_path.string() + ": --" + flag +
                          " is a build option an update keeps from the index" + kFullBuildNeeded);
    }
    const std::optional<OptionValue> built = spec.get(parent.options, parent.flags);
    const std::string built_text = built ? FormatOptionValue(*built) : "(none)";
    if (!built || built_text != FormatOptionValue(value)) {
      throw UpdateRefused(options.index_path.string() + ": the index was built with --" + flag +
                          " " + built_text + ", and this update asks for --" + flag + " " +
                          FormatOptionValue(value) + kFullBuildNeeded);
    }
  }
}

double Distance(const double* a, const double* b) {
  return (Eigen::Map<const Eigen::Vector3d>(a) - Eigen::Map<const Eigen::Vector3d>(b)).norm();
}

IndexUpdateReport Rebuild(const IndexUpdateOptions& options, const ParentBuild& parent,
                          const std::string& reason) {
  if (parent.georeferenced) {
    bool georef_given = false;
    for (const auto& [flag, value] : options.build_flags)
      georef_given |= flag == "georef" || flag == "georef-images" || flag == "model-frame";
    if (!georef_given) {
      throw UpdateRefused(reason +
                          "; --rebuild-if-needed cannot georeference the rebuilt index "
                          "without the build's --georef, --georef-images or --model-frame");
    }
  }
  IndexBuildOptions build = parent.options;
  IndexBuildFlags flags = parent.flags;
  for (const auto& [flag, value] : options.build_flags)
    FindBuildOption(flag).set(value, &build, &flags);
  build.model_dir = options.model_dir;
  build.database_path = options.database_path;
  build.output_path = options.output_path;
  build.threads = options.threads;
  ValidateBuildOptions(build, flags);
  ApplyBuildFlags(flags, &build);
  const IndexBuildReport built = BuildIndex(build);
  IndexUpdateReport report;
  report.rebuilt = true;
  report.rebuild_reason = reason;
  report.num_images = built.num_images;
  report.num_points = built.num_points;
  report.num_views = built.num_views;
  report.num_clusters = built.num_clusters;
  report.file_bytes = built.file_bytes;
  report.seconds_total = built.seconds_total;
  return report;
}

// A compact index codes each point by the mean of its views' descriptors: an old point that
// gained or lost views is coded anew, and the delta carries it as a new point (its old row
// leaves the kd-forest, its new one is inserted). Returns how many.
size_t RecodeChangedPoints(const Index& parent, const ModelViews& child, Correspondence* match) {
  std::vector<uint32_t> kept_views(child.points.size(), 0);
  for (uint32_t w = 0; w < child.num_views(); ++w)
    kept_views[child.view_points[w]] += match->parent_of_child_view[w] != kRemovedRow;
  size_t recoded = 0;
  for (uint32_t q = 0; q < child.points.size(); ++q) {
    const uint32_t p = match->parent_of_child_point[q];
    if (p == kRemovedRow) continue;
    if (kept_views[q] == parent.TrackOf(p).size() && kept_views[q] == child.points[q].track_length)
      continue;
    match->parent_of_child_point[q] = kRemovedRow;
    match->child_of_parent_point[p] = kRemovedRow;
    ++recoded;
  }
  return recoded;
}

// PVNN of a compact child: a point with a view in a changed cluster (`computed` on entry) gets
// it afresh, the smallest over all its clusters, which are computed too; the others keep the
// parent's, as nothing they see changed. `codes`: the child's, points x code bytes.
std::vector<float> CompactNeighborDistances(const Index& parent, ModelViews& child,
                                            const Clustering& clustering,
                                            const std::vector<uint32_t>& image_of_view,
                                            const std::vector<uint32_t>& parent_of_child_point,
                                            std::span<const uint8_t> codes,
                                            std::vector<bool> computed, int threads,
                                            size_t* clusters_computed) {
  const size_t num_points = child.points.size();
  const auto cluster_of_view = [&](uint32_t w) { return child.images[image_of_view[w]].cluster; };
  std::vector<bool> affected(num_points, false);
  for (uint32_t w = 0; w < child.num_views(); ++w)
    if (computed[cluster_of_view(w)]) affected[child.view_points[w]] = true;
  for (uint32_t w = 0; w < child.num_views(); ++w)
    if (affected[child.view_points[w]]) computed[cluster_of_view(w)] = true;
  *clusters_computed = size_t(std::count(computed.begin(), computed.end(), true));

  const std::vector<uint8_t> decoded =
      DescriptorCodes{parent.codes().codebook, codes, parent.codes().code_bytes}.DecodeAll();
  std::vector<float> distances =
      ComputePointNeighborDistances(&child, decoded, clustering, threads, &computed);
  for (uint32_t q = 0; q < num_points; ++q) {
    const uint32_t from = parent_of_child_point[q];
    if (from != kRemovedRow && !affected[q]) distances[q] = parent.point_neighbor_distances()[from];
  }
  return distances;
}

// The parent's checksums: those of the sections the read stage indexes by first; the bulk ones,
// which it reads as bytes (descriptors) or not at all (the kd-forest), meanwhile on a second
// thread, where a parent read from disk costs seconds, and the forest's structure after them.
// Returns that thread's future (none: all done).
std::future<void> VerifyParent(const Index& parent, int threads) {
  const auto bulk = [](uint32_t tag) {
    return tag == section::kDescriptors || tag == section::kKdNodes || tag == section::kKdLeaves;
  };
  parent.file().VerifyChecksums([&](uint32_t tag) { return !bulk(tag); });
  const auto verify_bulk = [&parent, bulk] {
    parent.file().VerifyChecksums(bulk);
    CheckParentKdForest(parent);
  };
  if (ResolveThreads(threads) > 1) return std::async(std::launch::async, verify_bulk);
  verify_bulk();
  return {};
}

// The parent's manifest, of an index that is no tile.
nlohmann::ordered_json ParentManifest(const Index& parent) {
  const std::string parent_name = parent.file().path().string();
  nlohmann::ordered_json manifest =
      nlohmann::ordered_json::parse(parent.manifest_json(), nullptr, false);
  if (manifest.is_discarded()) throw InputError(parent_name + ": section 'MANI' is not valid JSON");
  if (manifest.contains("extracted")) {
    throw InputError(parent_name +
                     ": a tile (cwloc-index extract) is not updated: update the index it was "
                     "cut from, then extract the tile with --parent-tile and --delta");
  }
  return manifest;
}

// What an update asks of the parent before the model is read: the build flags it was built
// with, and the point ids it follows the model's points by.
void CheckUpdatable(const IndexUpdateOptions& options, const ParentBuild& parent_build,
                    const Index& parent) {
  CheckBuildFlags(options, parent_build);
  if (parent.point_ids().empty()) {
    throw UpdateRefused(options.index_path.string() +
                        ": the index has no point ids (section PIDS, written since format 1.5) "
                        "to recognize the model's points by" +
                        kFullBuildNeeded);
  }
}

// The grown model, gathered as a build gathers it, once the parent's checksums are verified: a
// corrupt parent is the error to report.
GrownModel ReadGrown(const IndexUpdateOptions& options, const Index& parent,
                     const colmap::DatabaseReader& database, std::future<void>* bulk_verified) {
  const auto wait_bulk_verified = [&] {
    if (bulk_verified->valid()) bulk_verified->get();
  };
  GrownModel grown = [&] {
    try {
      return ReadGrownModel(options, parent, database);
    } catch (...) {
      wait_bulk_verified();
      throw;
    }
  }();
  wait_bulk_verified();
  parent.file().MapAllPages();
  if (grown.views.num_views() == 0)
    throw InputError(options.model_dir.string() + ": the model has no 3D points with views");
  return grown;
}

// The child's points no parent point is (new, or a compact index's re-coded ones), ascending.
std::vector<uint32_t> NewPointRows(const Correspondence& match) {
  std::vector<uint32_t> rows;
  for (uint32_t p = 0; p < match.parent_of_child_point.size(); ++p)
    if (match.parent_of_child_point[p] == kRemovedRow) rows.push_back(p);
  return rows;
}

// Old points may be refined (a bundle adjustment with fixed poses), not moved far: refuses a
// median move past kMaxMedianPointShift of the cameras' extent.
void CheckPointShifts(const IndexUpdateOptions& options, const Index& parent,
                      const ModelViews& child, const Correspondence& match) {
  std::vector<double> shifts;
  for (uint32_t p = 0; p < child.points.size(); ++p) {
    const uint32_t from = match.parent_of_child_point[p];
    if (from != kRemovedRow)
      shifts.push_back(Distance(parent.PointXyz(from).data(), child.points[p].xyz));
  }
  if (shifts.empty()) return;
  std::nth_element(shifts.begin(), shifts.begin() + shifts.size() / 2, shifts.end());
  const double median = shifts[shifts.size() / 2];
  if (median > kMaxMedianPointShift * match.extent) {
    char text[200];
    std::snprintf(text, sizeof(text),
                  ": the old 3D points moved by %.3g in the median (%.2g of the cameras' "
                  "extent): the model was adjusted again, not grown",
                  median, median / match.extent);
    throw UpdateRefused(options.model_dir.string() + text + kFullBuildNeeded);
  }
}

// Images, views and points added and removed.
void CountChanges(const Index& parent, const ModelViews& child, const Correspondence& match,
                  size_t new_points, IndexUpdateReport* report) {
  for (uint32_t parent_image : match.child_of_parent_image)
    report->images_removed += parent_image == kRemovedRow;
  for (uint32_t v : match.parent_of_child_view) report->views_added += v == kRemovedRow;
  report->views_removed = parent.num_views() - (child.num_views() - report->views_added);
  report->points_added = new_points - report->points_recoded;
  report->points_removed = parent.num_points() - (child.points.size() - report->points_added);
}

// The image (row) of each of the child's views.
std::vector<uint32_t> ImageOfView(const ModelViews& child) {
  std::vector<uint32_t> image_of_view(child.num_views());
  for (uint32_t i = 0; i < child.images.size(); ++i)
    std::fill_n(image_of_view.begin() + child.images[i].first_view, child.images[i].num_views, i);
  return image_of_view;
}

// A compact child's codes: the parent's, and its codebook's for new and re-coded points, whose
// views' descriptors the gather read.
OwnedRows<uint8_t> CompactChildCodes(const Index& parent, const GrownModel& grown,
                                     const Correspondence& match,
                                     std::span<const uint32_t> new_point_rows,
                                     std::span<const uint32_t> image_of_view, int threads) {
  const ModelViews& child = grown.views;
  for (uint32_t q : new_point_rows) {
    const IndexPoint& point = child.points[q];
    for (uint32_t t = point.first_track; t < point.first_track + point.track_length; ++t) {
      if (grown.unread_images.count(child.images[image_of_view[child.tracks[t]]].image_id))
        throw std::logic_error("update: a point coded anew is seen by an image not read");
    }
  }
  const DescriptorCodes& parent_codes = parent.codes();
  return ChildCodes(parent_codes, match.parent_of_child_point,
                    CodePointsWithCodebook(child, new_point_rows, parent_codes.codebook,
                                           parent_codes.code_bytes, threads));
}

// Images whose views changed their points change their clusters' v_NN.
void MarkImagesWithMovedViews(const Index& parent, const ModelViews& child,
                              std::span<const uint32_t> image_of_view, Correspondence* match) {
  for (uint32_t w = 0; w < child.num_views(); ++w) {
    const uint32_t v = match->parent_of_child_view[w];
    if (v != kRemovedRow &&
        match->child_of_parent_point[parent.view_points()[v]] != child.view_points[w])
      match->image_changed[image_of_view[w]] = true;
  }
}

// Clusters of a child clustered by co-visibility or a file: an old image keeps its own, a new
// one joins the cluster of the old image it shares the most points with (one of its own when it
// shares none). `lost_member`: the clusters an old image left.
Clustering JoinParentClusters(const Index& parent, const ModelViews& child,
                              const Correspondence& match, int threads,
                              std::vector<uint32_t>* lost_member) {
  const std::span<const IndexImage> parent_images = parent.images();
  const std::vector<uint32_t>& parent_of_image = match.parent_of_child_image;
  // The graph joins new images to clusters; apply makes the index's own.
  const CovisibilityGraph graph =
      BuildCovisibilityGraph(child.images, child.points, child.tracks, child.view_points, threads);
  // Old cluster ids first, then one id per new image that shares nothing with an old one.
  std::vector<uint64_t> raw(child.images.size(), UINT64_MAX);
  for (uint32_t i = 0; i < child.images.size(); ++i) {
    if (parent_of_image[i] != kRemovedRow) raw[i] = parent_images[parent_of_image[i]].cluster;
  }
  uint64_t next_id = parent_images.size();
  for (uint32_t i = 0; i < child.images.size(); ++i) {
    if (raw[i] != UINT64_MAX) continue;
    uint32_t best_shared = 0;
    for (uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
      const CovisibilityEdge& edge = graph.edges[e];
      const uint32_t other = parent_of_image[edge.image_index];
      if (other != kRemovedRow && edge.shared_points > best_shared) {
        best_shared = edge.shared_points;
        raw[i] = parent_images[other].cluster;
      }
    }
    if (raw[i] == UINT64_MAX) raw[i] = next_id++;
  }
  std::map<uint64_t, uint32_t> dense;
  for (uint64_t id : raw) dense.emplace(id, 0);
  uint32_t next = 0;
  for (auto& [id, value] : dense) value = next++;
  Clustering clustering;
  for (uint64_t id : raw) clustering.cluster_of_image.push_back(dense[id]);
  clustering.num_clusters = next;
  for (uint32_t i = 0; i < parent_images.size(); ++i) {
    if (match.child_of_parent_image[i] == kRemovedRow && dense.count(parent_images[i].cluster))
      lost_member->push_back(dense[parent_images[i].cluster]);
  }
  return clustering;
}

// The child's clustering, set on its images, and the clusters whose v_NN is computed afresh:
// those with a new, changed or removed image. One cluster per image stays so.
struct ChildClusters {
  Clustering clustering;
  std::vector<bool> recomputed;
};
ChildClusters ClusterChild(const Index& parent, const ParentBuild& parent_build,
                           const std::string& method, const Correspondence& match, int threads,
                           ModelViews* child, IndexUpdateReport* report) {
  ChildClusters clusters;
  Clustering& clustering = clusters.clustering;
  std::vector<uint32_t> lost_member;
  if (parent_build.options.clustering.method == ClusteringMethod::kPerImage) {
    for (uint32_t i = 0; i < child->images.size(); ++i) clustering.cluster_of_image.push_back(i);
    clustering.num_clusters = uint32_t(child->images.size());
  } else {
    clustering = JoinParentClusters(parent, *child, match, threads, &lost_member);
  }
  clustering.method = method;
  for (uint32_t i = 0; i < child->images.size(); ++i)
    child->images[i].cluster = clustering.cluster_of_image[i];
  std::vector<bool>& recomputed = clusters.recomputed;
  recomputed.assign(clustering.num_clusters, false);
  for (uint32_t i = 0; i < child->images.size(); ++i) {
    const bool added = match.parent_of_child_image[i] == kRemovedRow;
    report->images_added += added;
    report->images_changed += !added && match.image_changed[i];
    if (match.image_changed[i]) recomputed[clustering.cluster_of_image[i]] = true;
  }
  for (uint32_t c : lost_member) recomputed[c] = true;
  for (bool d : recomputed) report->clusters_recomputed += d;
  return clusters;
}

// A full child's v_NN: afresh in the clusters recomputed, which read their old images' rows (the
// gather left them to the index), the parent's elsewhere.
std::vector<float> FullNeighborDistances(const Index& parent, GrownModel* grown,
                                         const ChildClusters& clusters,
                                         std::span<const uint32_t> image_of_view,
                                         const Correspondence& match, int threads) {
  ModelViews& child = grown->views;
  const std::vector<bool>& recomputed = clusters.recomputed;
  const std::vector<uint32_t>& cluster_of_image = clusters.clustering.cluster_of_image;
  for (uint32_t i = 0; i < child.images.size(); ++i) {
    const uint32_t from = match.parent_of_child_image[i];
    if (from != kRemovedRow && grown->rows_reused[from] && recomputed[cluster_of_image[i]])
      WriteRowsFromIndex(parent, parent.images()[from], child.images[i], &child);
  }
  std::vector<float> distances =
      ComputeViewNeighborDistances(child, clusters.clustering, threads, &recomputed);
  for (uint32_t w = 0; w < child.num_views(); ++w) {
    const uint32_t v = match.parent_of_child_view[w];
    if (v != kRemovedRow && !recomputed[child.images[image_of_view[w]].cluster])
      distances[w] = parent.view_neighbor_distances()[v];
  }
  return distances;
}

// The child's manifest: the parent's, with the child's counts, clusters, model and update record.
nlohmann::ordered_json ChildManifest(const IndexUpdateOptions& options,
                                     const nlohmann::ordered_json& parent_manifest,
                                     const GrownModel& grown, uint32_t num_clusters,
                                     const AppliedDelta& applied, const ChildUpdate& next) {
  const ModelViews& child = grown.views;
  nlohmann::ordered_json manifest = parent_manifest;
  manifest["tool_version"] = kToolVersion;
  IndexBuildReport counts;
  counts.num_cameras = child.cameras.size();
  counts.num_images = child.images.size();
  counts.num_points = child.points.size();
  counts.num_views = child.num_views();
  counts.num_clusters = num_clusters;
  counts.num_covisibility_edges = applied.num_covisibility_edges();
  manifest["counts"] = CountsJson(counts);
  manifest["counts"]["kd_nodes"] = applied.num_kd_nodes();
  manifest["build_parameters"]["clustering"]["num_clusters"] = num_clusters;
  manifest["source"]["model"]["path"] = options.model_dir.string();
  manifest["source"]["model"]["layout"] = grown.layout;
  manifest["source"]["model"]["fingerprint"] = FingerprintModel(options.model_dir);
  manifest["source"]["database"]["path"] = options.database_path.string();
  manifest["update"] = next.record;
  return manifest;
}

// The child composed from the parent and the delta, as a device applies it, written with its
// manifest, then the delta, which names the child's checksum.
void ApplyAndWrite(const IndexUpdateOptions& options, const Index& parent,
                   const nlohmann::ordered_json& parent_manifest, GrownModel* grown,
                   uint32_t num_clusters, size_t rows_inserted, IndexDelta* delta,
                   IndexUpdateReport* report) {
  Stopwatch stage;
  ModelViews& child = grown->views;
  // The kd-forest's rows: views, or a compact index's points (new and re-coded ones).
  const ChildUpdate next =
      NextUpdate(parent_manifest, parent, report->coded ? child.points.size() : child.num_views(),
                 rows_inserted, report->images_added, report->images_removed, &delta->header);
  report->forest_rebuilt = next.forest_rebuilt;
  // The child's other rows come from the delta and the parent, as on a device.
  decltype(child.descriptors)().swap(child.descriptors);
  const AppliedDelta applied(parent, *delta, "the update", options.output_path,
                             ResolveThreads(options.threads), AppliedDelta::ParentForest::kChecked);
  report->seconds_apply = stage.Seconds();
  stage.Restart();

  report->num_images = child.images.size();
  report->num_points = child.points.size();
  report->num_views = child.num_views();
  report->num_clusters = num_clusters;
  delta->manifest =
      ChildManifest(options, parent_manifest, *grown, num_clusters, applied, next).dump(2) + "\n";
  delta->header.child_checksum = applied.Write(delta->manifest, std::nullopt);
  report->file_bytes = std::filesystem::file_size(options.output_path);
  delta->header.child_file_size = report->file_bytes;
  if (!options.delta_path.empty()) {
    WriteDelta(options.delta_path, *delta);
    report->delta_bytes = std::filesystem::file_size(options.delta_path);
  }
  report->seconds_write = stage.Seconds();
}

// The update once the parent may be updated: read the grown model, compare it with the parent,
// cluster it and measure its v_NN, make the delta, apply and write.
IndexUpdateReport UpdateFromModel(const IndexUpdateOptions& options, const Index& parent,
                                  const nlohmann::ordered_json& parent_manifest,
                                  const ParentBuild& parent_build,
                                  std::future<void>* bulk_verified) {
  IndexUpdateReport report;
  Stopwatch stage;
  const colmap::DatabaseReader database(options.database_path);
  GrownModel grown = ReadGrown(options, parent, database, bulk_verified);
  ModelViews& child = grown.views;
  report.images_read = grown.images_read;
  report.seconds_read = stage.Seconds();

  stage.Restart();
  const int threads = ResolveThreads(options.threads);
  Correspondence match = MatchToParent(options, parent, grown, database);
  report.coded = parent.coded();
  if (report.coded) report.points_recoded = RecodeChangedPoints(parent, child, &match);
  const std::vector<uint32_t> new_point_rows = NewPointRows(match);
  CountChanges(parent, child, match, new_point_rows.size(), &report);
  CheckPointShifts(options, parent, child, match);
  const std::vector<uint32_t> image_of_view = ImageOfView(child);
  const OwnedRows<uint8_t> codes =
      report.coded ? CompactChildCodes(parent, grown, match, new_point_rows, image_of_view, threads)
                   : OwnedRows<uint8_t>();
  MarkImagesWithMovedViews(parent, child, image_of_view, &match);
  report.seconds_compare = stage.Seconds();

  stage.Restart();
  const ChildClusters clusters =
      ClusterChild(parent, parent_build,
                   parent_manifest["build_parameters"]["clustering"]["method"].get<std::string>(),
                   match, threads, &child, &report);
  const std::vector<float> neighbor_distances =
      report.coded
          ? CompactNeighborDistances(parent, child, clusters.clustering, image_of_view,
                                     match.parent_of_child_point, codes, clusters.recomputed,
                                     threads, &report.clusters_recomputed)
          : FullNeighborDistances(parent, &grown, clusters, image_of_view, match, threads);
  DeltaChild delta_child{child.Borrow(), match.parent_of_child_view, match.parent_of_child_point};
  (report.coded ? delta_child.rows.point_neighbor_distances
                : delta_child.rows.view_neighbor_distances) = neighbor_distances;
  delta_child.rows.codes = codes;
  IndexDelta delta = MakeDelta(parent, delta_child);
  report.neighbor_distances_changed = delta.view_neighbor_changes.size();
  report.points_moved = delta.point_moves.size();
  report.seconds_neighbor_distances = stage.Seconds();

  const size_t rows_inserted = report.coded ? new_point_rows.size() : report.views_added;
  ApplyAndWrite(options, parent, parent_manifest, &grown, clusters.clustering.num_clusters,
                rows_inserted, &delta, &report);
  return report;
}

}  // namespace

IndexUpdateReport UpdateIndex(const IndexUpdateOptions& options) {
  const Stopwatch total;
  const Index parent = Index::Open(options.index_path);
  std::future<void> bulk_verified = VerifyParent(parent, options.threads);
  const nlohmann::ordered_json parent_manifest = ParentManifest(parent);
  const ParentBuild parent_build = ParentBuildOf(parent_manifest);
  if (!options.delta_path.empty() && options.delta_path == options.output_path)
    throw InputError(options.delta_path.string() + ": the delta and the index are one file");
  try {
    CheckUpdatable(options, parent_build, parent);
    IndexUpdateReport report =
        UpdateFromModel(options, parent, parent_manifest, parent_build, &bulk_verified);
    report.seconds_total = total.Seconds();
    return report;
  } catch (const UpdateRefused& refused) {
    if (!options.rebuild_if_needed) throw;
    return Rebuild(options, parent_build, refused.what());
  }
}

ChildUpdate NextUpdate(const nlohmann::ordered_json& parent_manifest, const Index& parent,
                       size_t child_rows, size_t rows_inserted, size_t images_added,
                       size_t images_removed, DeltaHeader* header) {
  const nlohmann::ordered_json before =
      parent_manifest.value("update", nlohmann::ordered_json::object());
  uint64_t rows_at_build = before.value("forest_rows_at_build", uint64_t(parent.num_rows()));
  uint64_t inserted = before.value("forest_rows_inserted", uint64_t{0}) + rows_inserted;
  ChildUpdate next;
  next.forest_rebuilt = double(inserted) > kForestRebuildFraction * double(rows_at_build);
  if (next.forest_rebuilt) rows_at_build = child_rows, inserted = 0;
  const auto& parameters = parent_manifest.at("build_parameters");
  header->forest_seed = parameters.at("seed").get<uint64_t>();
  header->forest_leaf_size = parameters.at("kd_leaf_size").get<uint32_t>();
  header->flags = next.forest_rebuilt ? kDeltaForestRebuilt : 0;
  next.record = {{"updates", before.value("updates", uint64_t{0}) + 1},
                 {"images_added", before.value("images_added", uint64_t{0}) + images_added},
                 {"images_removed", before.value("images_removed", uint64_t{0}) + images_removed},
                 {"forest_rows_at_build", rows_at_build},
                 {"forest_rows_inserted", inserted},
                 {"parent",
                  {{"checksum", "xxh64:" + HashHex(header->parent_checksum)},
                   {"file_bytes", header->parent_file_size}}}};
  return next;
}

nlohmann::ordered_json UpdateReportJson(const IndexUpdateOptions& options,
                                        const IndexUpdateReport& report) {
  nlohmann::ordered_json out = {{"output", options.output_path.string()},
                                {"file_bytes", report.file_bytes},
                                {"rebuilt", report.rebuilt}};
  if (report.rebuilt) out["rebuild_reason"] = report.rebuild_reason;
  if (!options.delta_path.empty() && !report.rebuilt) {
    out["delta"] = {{"path", options.delta_path.string()}, {"bytes", report.delta_bytes}};
  }
  out["counts"] = {{"images", report.num_images},
                   {"points", report.num_points},
                   {"views", report.num_views},
                   {"clusters", report.num_clusters}};
  out["changes"] = {{"images_added", report.images_added},
                    {"images_removed", report.images_removed},
                    {"images_changed", report.images_changed},
                    {"views_added", report.views_added},
                    {"views_removed", report.views_removed},
                    {"points_added", report.points_added},
                    {"points_removed", report.points_removed},
                    {"points_moved", report.points_moved},
                    {"points_recoded", report.points_recoded},
                    {"clusters_recomputed", report.clusters_recomputed},
                    {"neighbor_distances_changed", report.neighbor_distances_changed},
                    {"forest_rebuilt", report.forest_rebuilt}};
  out["database"] = {{"images_read", report.images_read}};
  out["seconds"] = {{"read", report.seconds_read},
                    {"compare", report.seconds_compare},
                    {"neighbor_distances", report.seconds_neighbor_distances},
                    {"apply", report.seconds_apply},
                    {"write", report.seconds_write},
                    {"total", report.seconds_total}};
  return out;
}

}  // namespace cwloc
