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

}  // namespace

IndexUpdateReport UpdateIndex(const IndexUpdateOptions& options) {
  const Stopwatch total;
  IndexUpdateReport report;
  const std::string parent_name = options.index_path.string();
  const Index parent = Index::Open(options.index_path);
  // The sections the read stage indexes by are checked before it; the bulk ones, which it reads
  // as bytes (descriptors) or not at all (the kd-forest), meanwhile on a second thread, where a
  // parent read from disk costs seconds, and the forest's structure after them.
  const auto bulk = [](uint32_t tag) {
    return tag == section::kDescriptors || tag == section::kKdNodes || tag == section::kKdLeaves;
  };
  parent.file().VerifyChecksums([&](uint32_t tag) { return !bulk(tag); });
  const auto verify_bulk = [&] {
    parent.file().VerifyChecksums(bulk);
    CheckParentKdForest(parent);
  };
  std::future<void> bulk_verified;
  if (ResolveThreads(options.threads) > 1) {
    bulk_verified = std::async(std::launch::async, verify_bulk);
  } else {
    verify_bulk();
  }
  const auto wait_bulk_verified = [&] {
    if (bulk_verified.valid()) bulk_verified.get();
  };
  const nlohmann::ordered_json parent_manifest =
      nlohmann::ordered_json::parse(parent.manifest_json(), nullptr, false);
  if (parent_manifest.is_discarded())
    throw InputError(parent_name + ": section 'MANI' is not valid JSON");
  if (parent_manifest.contains("extracted")) {
    throw InputError(parent_name +
                     ": a tile (cwloc-index extract) is not updated: update the index it was "
                     "cut from, then extract the tile with --parent-tile and --delta");
  }
  const ParentBuild parent_build = ParentBuildOf(parent_manifest);
  if (!options.delta_path.empty() && options.delta_path == options.output_path)
    throw InputError(options.delta_path.string() + ": the delta and the index are one file");
  try {
    CheckBuildFlags(options, parent_build);
    if (parent.point_ids().empty()) {
      throw UpdateRefused(parent_name +
                          ": the index has no point ids (section PIDS, written since format 1.5) "
                          "to recognize the model's points by" +
                          kFullBuildNeeded);
    }
  } catch (const UpdateRefused& refused) {
    if (!options.rebuild_if_needed) throw;
    return Rebuild(options, parent_build, refused.what());
  }

  // The grown model, gathered as a build gathers it.
  Stopwatch stage;
  try {
    const colmap::DatabaseReader database(options.database_path);
    GrownModel grown = [&] {
      try {
        return ReadGrownModel(options, parent, database);
      } catch (...) {
        wait_bulk_verified();  // a corrupt parent is the error to report
        throw;
      }
    }();
    wait_bulk_verified();
    parent.file().MapAllPages();
    ModelViews& child = grown.views;
    if (child.num_views() == 0)
      throw InputError(options.model_dir.string() + ": the model has no 3D points with views");
    report.images_read = grown.images_read;
    report.seconds_read = stage.Seconds();

    stage.Restart();
    {
      Correspondence match = MatchToParent(options, parent, grown, database);
      const bool coded = report.coded = parent.coded();
      if (coded) report.points_recoded = RecodeChangedPoints(parent, child, &match);
      const int threads = ResolveThreads(options.threads);
      const std::span<const IndexImage> parent_images = parent.images();
      const std::vector<uint32_t>& child_of_parent_image = match.child_of_parent_image;
      const std::vector<uint32_t>& parent_of_child_image = match.parent_of_child_image;
      const std::vector<uint32_t>& parent_of_child_view = match.parent_of_child_view;
      const std::vector<uint32_t>& child_of_parent_point = match.child_of_parent_point;
      const std::vector<uint32_t>& parent_of_child_point = match.parent_of_child_point;
      std::vector<bool> image_changed = match.image_changed;
      const double extent = match.extent;
      for (uint32_t parent_image : child_of_parent_image)
        report.images_removed += parent_image == kRemovedRow;
      for (uint32_t v : parent_of_child_view) report.views_added += v == kRemovedRow;
      report.views_removed = parent.num_views() - (child.num_views() - report.views_added);

      // Old points may be refined (a bundle adjustment with fixed poses), not moved far.
      std::vector<double> shifts;
      std::vector<uint32_t> new_point_rows;
      for (uint32_t p = 0; p < child.points.size(); ++p) {
        const uint32_t from = parent_of_child_point[p];
        if (from == kRemovedRow) {
          new_point_rows.push_back(p);
          continue;
        }
        shifts.push_back(Distance(parent.PointXyz(from).data(), child.points[p].xyz));
      }
      report.points_added = new_point_rows.size() - report.points_recoded;
      report.points_removed = parent.num_points() - (child.points.size() - report.points_added);
      if (!shifts.empty()) {
        std::nth_element(shifts.begin(), shifts.begin() + shifts.size() / 2, shifts.end());
        const double median = shifts[shifts.size() / 2];
        if (median > kMaxMedianPointShift * extent) {
          char text[200];
          std::snprintf(text, sizeof(text),
                        ": the old 3D points moved by %.3g in the median (%.2g of the cameras' "
                        "extent): the model was adjusted again, not grown",
                        median, median / extent);
          throw UpdateRefused(options.model_dir.string() + text + kFullBuildNeeded);
        }
      }
      std::vector<uint32_t> image_of_view(child.num_views());
      for (uint32_t i = 0; i < child.images.size(); ++i)
        std::fill_n(image_of_view.begin() + child.images[i].first_view, child.images[i].num_views,
                    i);
      // A compact index's codes: the parent's, and its codebook's for new and re-coded points.
      std::vector<uint8_t> codes;
      if (coded) {
        for (uint32_t q : new_point_rows) {
          const IndexPoint& point = child.points[q];
          for (uint32_t t = point.first_track; t < point.first_track + point.track_length; ++t) {
            if (grown.unread_images.count(child.images[image_of_view[child.tracks[t]]].image_id))
              throw std::logic_error("update: a point coded anew is seen by an image not read");
          }
        }
        const DescriptorCodes& parent_codes = parent.codes();
        codes = ChildCodes(parent_codes, parent_of_child_point,
                           CodePointsWithCodebook(child, new_point_rows, parent_codes.codebook,
                                                  parent_codes.code_bytes, threads));
      }

      // Images whose views changed their points change their clusters' v_NN.
      for (uint32_t w = 0; w < child.num_views(); ++w) {
        const uint32_t v = parent_of_child_view[w];
        if (v != kRemovedRow &&
            child_of_parent_point[parent.view_points()[v]] != child.view_points[w])
          image_changed[image_of_view[w]] = true;
      }
      report.seconds_compare = stage.Seconds();

      // Clusters: an old image keeps its own, a new one joins the cluster of the old image it
      // shares the most points with (a cluster of its own when it shares none); one cluster per
      // image stays so. Clusters with a new, changed or removed image get their v_NN afresh.
      stage.Restart();
      const bool per_image = parent_build.options.clustering.method == ClusteringMethod::kPerImage;
      // The graph joins new images to clusters; apply makes the index's own.
      const CovisibilityGraph graph =
          per_image ? CovisibilityGraph{}
                    : BuildCovisibilityGraph(child.images, child.points, child.tracks,
                                             child.view_points, threads);
      Clustering clustering;
      clustering.method =
          parent_manifest["build_parameters"]["clustering"]["method"].get<std::string>();
      std::vector<uint32_t> lost_member;  // clusters an old image left
      if (per_image) {
        for (uint32_t i = 0; i < child.images.size(); ++i) clustering.cluster_of_image.push_back(i);
        clustering.num_clusters = uint32_t(child.images.size());
      } else {
        // Old cluster ids first, then one id per new image that shares nothing with an old one.
        std::vector<uint64_t> raw(child.images.size(), UINT64_MAX);
        for (uint32_t i = 0; i < child.images.size(); ++i) {
          if (parent_of_child_image[i] != kRemovedRow)
            raw[i] = parent_images[parent_of_child_image[i]].cluster;
        }
        uint64_t next_id = parent_images.size();
        for (uint32_t i = 0; i < child.images.size(); ++i) {
          if (raw[i] != UINT64_MAX) continue;
          uint32_t best_shared = 0;
          for (uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
            const CovisibilityEdge& edge = graph.edges[e];
            const uint32_t other = parent_of_child_image[edge.image_index];
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
        for (uint64_t id : raw) clustering.cluster_of_image.push_back(dense[id]);
        clustering.num_clusters = next;
        for (uint32_t i = 0; i < parent_images.size(); ++i) {
          if (child_of_parent_image[i] == kRemovedRow && dense.count(parent_images[i].cluster))
            lost_member.push_back(dense[parent_images[i].cluster]);
        }
      }
      for (uint32_t i = 0; i < child.images.size(); ++i)
        child.images[i].cluster = clustering.cluster_of_image[i];
      std::vector<bool> dirty(clustering.num_clusters, false);
      for (uint32_t i = 0; i < child.images.size(); ++i) {
        report.images_added += parent_of_child_image[i] == kRemovedRow;
        report.images_changed += parent_of_child_image[i] != kRemovedRow && image_changed[i];
        if (image_changed[i]) dirty[clustering.cluster_of_image[i]] = true;
      }
      for (uint32_t c : lost_member) dirty[c] = true;
      for (bool d : dirty) report.clusters_recomputed += d;
      // The child's v_NN: afresh in the clusters recomputed, the parent's elsewhere.
      std::vector<float> neighbor_distances;
      if (coded) {
        neighbor_distances = CompactNeighborDistances(parent, child, clustering, image_of_view,
                                                      parent_of_child_point, codes, dirty, threads,
                                                      &report.clusters_recomputed);
      } else {
        // The clusters recomputed read their old images' rows, which the gather left to the index.
        for (uint32_t i = 0; i < child.images.size(); ++i) {
          const uint32_t from = parent_of_child_image[i];
          if (from != kRemovedRow && grown.rows_reused[from] &&
              dirty[clustering.cluster_of_image[i]])
            WriteRowsFromIndex(parent, parent_images[from], child.images[i], &child);
        }
        neighbor_distances = ComputeViewNeighborDistances(child, clustering, threads, &dirty);
        for (uint32_t w = 0; w < child.num_views(); ++w) {
          const uint32_t v = parent_of_child_view[w];
          if (v != kRemovedRow && !dirty[child.images[image_of_view[w]].cluster])
            neighbor_distances[w] = parent.view_neighbor_distances()[v];
        }
      }
      DeltaChild delta_child;
      delta_child.cameras = child.cameras;
      delta_child.images = child.images;
      delta_child.strings = child.strings;
      delta_child.parent_of_view = parent_of_child_view;
      delta_child.descriptors = child.descriptors;
      delta_child.view_points = child.view_points;
      delta_child.view_keypoints = child.view_keypoints;
      delta_child.neighbor_distances = neighbor_distances;
      delta_child.parent_of_point = parent_of_child_point;
      delta_child.points = child.points;
      delta_child.point_ids = child.point_ids;
      delta_child.point_colors = child.point_colors;
      delta_child.codes = codes;
      IndexDelta delta = MakeDelta(parent, delta_child);
      report.neighbor_distances_changed = delta.view_neighbor_changes.size();
      report.points_moved = delta.point_moves.size();
      report.seconds_neighbor_distances = stage.Seconds();

      // The kd-forest's rows: views, or a compact index's points (new and re-coded ones).
      stage.Restart();
      const ChildUpdate next =
          NextUpdate(parent_manifest, parent, coded ? child.points.size() : child.num_views(),
                     coded ? new_point_rows.size() : report.views_added, report.images_added,
                     report.images_removed, &delta.header);
      report.forest_rebuilt = next.forest_rebuilt;
      // The child's other rows come from the delta and the parent, as on a device.
      decltype(child.descriptors)().swap(child.descriptors);
      const AppliedDelta applied(parent, delta, "the update", options.output_path, threads,
                                 AppliedDelta::ParentForest::kChecked);
      report.seconds_apply = stage.Seconds();
      stage.Restart();

      report.num_images = child.images.size();
      report.num_points = child.points.size();
      report.num_views = child.num_views();
      report.num_clusters = clustering.num_clusters;
      nlohmann::ordered_json manifest = parent_manifest;
      manifest["tool_version"] = kToolVersion;
      IndexBuildReport counts;
      counts.num_cameras = child.cameras.size();
      counts.num_images = child.images.size();
      counts.num_points = child.points.size();
      counts.num_views = child.num_views();
      counts.num_clusters = clustering.num_clusters;
      counts.num_covisibility_edges = applied.num_covisibility_edges();
      manifest["counts"] = CountsJson(counts);
      manifest["counts"]["kd_nodes"] = applied.num_kd_nodes();
      manifest["build_parameters"]["clustering"]["num_clusters"] = clustering.num_clusters;
      manifest["source"]["model"]["path"] = options.model_dir.string();
      manifest["source"]["model"]["layout"] = grown.layout;
      manifest["source"]["model"]["fingerprint"] = FingerprintModel(options.model_dir);
      manifest["source"]["database"]["path"] = options.database_path.string();
      manifest["update"] = next.record;
      delta.manifest = manifest.dump(2) + "\n";
      delta.header.child_checksum = applied.Write(delta.manifest, std::nullopt);
      report.file_bytes = std::filesystem::file_size(options.output_path);
      delta.header.child_file_size = report.file_bytes;
      if (!options.delta_path.empty()) {
        WriteDelta(options.delta_path, delta);
        report.delta_bytes = std::filesystem::file_size(options.delta_path);
      }
      report.seconds_write = stage.Seconds();
    }
  } catch (const UpdateRefused& refused) {
    if (!options.rebuild_if_needed) throw;
    return Rebuild(options, parent_build, refused.what());
  }
  report.seconds_total = total.Seconds();
  return report;
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
