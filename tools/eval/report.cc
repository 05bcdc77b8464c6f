#include "tools/eval/report.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <unordered_map>

#include "base/chi_square.h"
#include "cwloc/version.h"

namespace cwloc::eval {
namespace {

using nlohmann::ordered_json;

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Enough digits for both centimetre errors in metres and sub-degree rotations.
std::string Number(double value) {
  const double magnitude = std::abs(value);
  if (magnitude != 0 && magnitude < 0.01) return Format("%.2g", value);
  if (magnitude < 10) return Format("%.3f", value);
  if (magnitude < 1000) return Format("%.1f", value);
  return Format("%.0f", value);
}

std::string QuartileCell(const std::optional<Quartiles>& q) {
  if (!q) return "-";
  return Number(q->q1) + " / " + Number(q->median) + " / " + Number(q->q3);
}

std::string TimeCell(const TimeQuantiles& q) { return QuartileCell(q) + " / " + Number(q.p90); }

std::string Percent(int count, int total) {
  return total == 0 ? "-" : Format("%.1f%%", 100.0 * count / total);
}

ordered_json QuartilesJson(const std::optional<Quartiles>& q) {
  if (!q) return nullptr;
  return {{"q1", q->q1}, {"median", q->median}, {"q3", q->q3}};
}

ordered_json TimeQuantilesJson(const TimeQuantiles& q) {
  ordered_json quantiles = QuartilesJson(q);
  quantiles["p90"] = q.p90;
  return quantiles;
}

std::string ThresholdName(const Threshold& t, const char* unit) {
  // Appending rather than "(" + string sidesteps a GCC 12 -Wrestrict false positive.
  std::string name = "(";
  name += Format("%g", t.position);
  name += std::string(" ") + unit + ", " + Format("%g", t.rotation_deg) + " deg)";
  return name;
}

// Left-aligned text columns separated by two spaces.
std::string Columns(const std::vector<std::vector<std::string>>& rows) {
  std::vector<size_t> width;
  for (const auto& row : rows) {
    width.resize(std::max(width.size(), row.size()));
    for (size_t c = 0; c < row.size(); ++c) width[c] = std::max(width[c], row[c].size());
  }
  std::string out;
  for (const auto& row : rows) {
    std::string line = "  ";
    for (size_t c = 0; c < row.size(); ++c) {
      line += row[c];
      if (c + 1 < row.size()) line += std::string(width[c] - row[c].size() + 2, ' ');
    }
    out += line + "\n";
  }
  return out;
}

}  // namespace

double Quantile(const std::vector<double>& sorted, double p) {
  const double h = p * double(sorted.size() - 1);
  const size_t lo = size_t(std::floor(h));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - double(lo)) * (sorted[hi] - sorted[lo]);
}

namespace {

Quartiles QuartilesOfSorted(const std::vector<double>& sorted) {
  return {Quantile(sorted, 0.25), Quantile(sorted, 0.5), Quantile(sorted, 0.75)};
}

}  // namespace

std::optional<Quartiles> ComputeQuartiles(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  return QuartilesOfSorted(values);
}

std::optional<TimeQuantiles> ComputeTimeQuantiles(std::vector<double> values) {
  if (values.empty()) return std::nullopt;
  std::sort(values.begin(), values.end());
  return TimeQuantiles{QuartilesOfSorted(values), Quantile(values, 0.9)};
}

const char* QueryStatusName(QueryStatus status) {
  switch (status) {
    case QueryStatus::kLocalized:
      return "localized";
    case QueryStatus::kNotLocalized:
      return "not_localized";
    case QueryStatus::kError:
      return "error";
    case QueryStatus::kMissing:
      return "missing";
  }
  return "missing";
}

namespace {

// The frames' modes in the file's order; nothing when no result has one.
std::optional<SequenceReport> EvaluateSequence(const RunResults& run,
                                               const std::vector<QueryOutcome>& outcomes) {
  std::unordered_map<std::string, const QueryOutcome*> by_name;
  for (const QueryOutcome& outcome : outcomes) by_name.emplace(outcome.name, &outcome);
  SequenceReport sequence;
  std::vector<double> tracked_errors, relocalized_errors;
  int without_pose = 0;
  for (const QueryResult& result : run.queries) {
    if (result.tracking_mode.empty()) continue;
    ++sequence.frames;
    const bool tracked = result.tracking_mode == "tracked";
    const bool relocalized = result.tracking_mode == "relocalized";
    sequence.tracked += tracked;
    sequence.relocalized += relocalized;
    sequence.lost += !tracked && !relocalized;
    without_pose = tracked || relocalized ? 0 : without_pose + 1;
    sequence.longest_without_pose = std::max(sequence.longest_without_pose, without_pose);
    const auto outcome = by_name.find(result.name);
    if (outcome == by_name.end() || outcome->second->status != QueryStatus::kLocalized) continue;
    (tracked ? tracked_errors : relocalized_errors).push_back(outcome->second->position_error);
  }
  if (sequence.frames == 0) return std::nullopt;
  sequence.tracked_error = ComputeQuartiles(std::move(tracked_errors));
  sequence.relocalized_error = ComputeQuartiles(std::move(relocalized_errors));
  sequence.with_pose_share = double(sequence.tracked + sequence.relocalized) / sequence.frames;
  return sequence;
}

// The rig frames by their reference cameras; nothing when no result is a rig's.
std::optional<RigReport> EvaluateRig(const RunResults& run,
                                     const std::vector<QueryOutcome>& outcomes) {
  std::unordered_map<std::string, const QueryOutcome*> by_name;
  for (const QueryOutcome& outcome : outcomes) by_name.emplace(outcome.name, &outcome);
  RigReport rig;
  std::vector<double> position, rotation;
  bool any = false;
  for (const QueryResult& result : run.queries) {
    any |= !result.rig_frame.empty();
    if (!result.rig_reference) continue;
    const auto outcome = by_name.find(result.name);
    if (outcome == by_name.end()) continue;  // a reference camera without ground truth
    ++rig.frames;
    if (outcome->second->status != QueryStatus::kLocalized) continue;
    ++rig.localized;
    position.push_back(outcome->second->position_error);
    rotation.push_back(outcome->second->rotation_error_deg);
  }
  if (!any) return std::nullopt;
  rig.position_error = ComputeQuartiles(std::move(position));
  rig.rotation_error_deg = ComputeQuartiles(std::move(rotation));
  return rig;
}

}  // namespace

RunReport EvaluateRun(const std::vector<NamedPose>& ground_truth, const RunResults& run,
                      double scale, const std::string& label, const GeoTruth& geo) {
  RunReport report;
  report.label = label;
  report.path = run.path;
  report.format = run.format;
  report.queries = int(ground_truth.size());

  std::unordered_map<std::string, const QueryResult*> by_name;
  for (const QueryResult& result : run.queries) by_name.emplace(result.name, &result);

  std::vector<double> position_errors, rotation_errors;
  std::vector<double> ground_errors, height_errors;                      // --index
  std::vector<double> geo_errors, geo_ground_errors, geo_height_errors;  // --gt-geo
  if (geo.true_positions) report.geo.emplace();
  report.enu_errors = geo.georeference != nullptr;
  for (const NamedPose& truth : ground_truth) {
    QueryOutcome outcome;
    outcome.name = truth.name;
    const auto it = by_name.find(truth.name);
    if (it == by_name.end()) {
      outcome.status = QueryStatus::kMissing;
      ++report.missing;
    } else if (it->second->status == ResultStatus::kError) {
      outcome.status = QueryStatus::kError;
      ++report.errors;
    } else if (it->second->status == ResultStatus::kNotLocalized) {
      outcome.status = QueryStatus::kNotLocalized;
      ++report.not_localized;
    } else {
      outcome.status = QueryStatus::kLocalized;
      outcome.position_error = scale * PositionError(*it->second->pose, truth.pose);
      outcome.rotation_error_deg = RotationErrorDeg(*it->second->pose, truth.pose);
      position_errors.push_back(outcome.position_error);
      rotation_errors.push_back(outcome.rotation_error_deg);
      for (size_t t = 0; t < kThresholds.size(); ++t) {
        if (outcome.position_error <= kThresholds[t].position &&
            outcome.rotation_error_deg <= kThresholds[t].rotation_deg) {
          ++report.within[t];
        }
      }
      ++report.localized;
      if (const auto& covariance = it->second->position_covariance) {
        const Eigen::Vector3d offset = it->second->pose->Center() - truth.pose.Center();
        outcome.inside95 = offset.dot(covariance->ldlt().solve(offset)) <= kChiSquare3Dof95;
        ++report.with_covariance;
        report.inside95 += *outcome.inside95;
      }
      if (geo.georeference) {
        outcome.enu_error = ErrorInIndexFrame(*geo.georeference, *it->second->pose, truth.pose);
        ground_errors.push_back(outcome.enu_error->ground);
        height_errors.push_back(outcome.enu_error->height);
      }
      if (geo.true_positions) {
        if (it->second->geo) {
          const auto position = geo.true_positions->find(truth.name);
          if (position == geo.true_positions->end()) {
            throw std::logic_error("cwloc-eval: no true position for " + truth.name);
          }
          outcome.geo_error = ErrorOnGlobe(*it->second->geo, position->second);
          geo_errors.push_back(outcome.geo_error->distance);
          geo_ground_errors.push_back(outcome.geo_error->ground);
          geo_height_errors.push_back(outcome.geo_error->height);
          ++report.geo->compared;
          if (outcome.geo_error->distance <= kGeoWithinMetres) ++report.geo->within;
        } else {
          ++report.geo->without_geo;
        }
      }
    }
    report.per_query.push_back(std::move(outcome));
  }

  std::unordered_map<std::string, bool> in_truth;
  for (const NamedPose& truth : ground_truth) in_truth.emplace(truth.name, true);
  std::array<std::vector<double>, kStageNames.size()> stage_values;
  for (const QueryResult& result : run.queries) {
    if (!in_truth.contains(result.name)) ++report.unknown_names;
    // Timing does not depend on the ground truth, so every timed record counts.
    if (!result.times_ms) continue;
    ++report.timed_records;
    for (size_t s = 0; s < kStageNames.size(); ++s)
      stage_values[s].push_back((*result.times_ms)[s]);
  }
  report.sequence = EvaluateSequence(run, report.per_query);
  report.rig = EvaluateRig(run, report.per_query);
  report.position_error = ComputeQuartiles(std::move(position_errors));
  report.rotation_error_deg = ComputeQuartiles(std::move(rotation_errors));
  report.ground_error = ComputeQuartiles(std::move(ground_errors));
  report.height_error = ComputeQuartiles(std::move(height_errors));
  if (report.geo) {
    report.geo->error = ComputeQuartiles(std::move(geo_errors));
    report.geo->ground_error = ComputeQuartiles(std::move(geo_ground_errors));
    report.geo->height_error = ComputeQuartiles(std::move(geo_height_errors));
  }
  if (report.timed_records > 0) {
    std::array<TimeQuantiles, kStageNames.size()> times;
    for (size_t s = 0; s < kStageNames.size(); ++s)
      times[s] = *ComputeTimeQuantiles(std::move(stage_values[s]));
    report.times_ms = times;
  }
  return report;
}

namespace {

// Each query's status and errors.
ordered_json PerQueryJson(const RunReport& run) {
  ordered_json per_query = ordered_json::array();
  for (const QueryOutcome& q : run.per_query) {
    ordered_json entry = {{"name", q.name}, {"status", QueryStatusName(q.status)}};
    if (q.status == QueryStatus::kLocalized) {
      entry["position_error"] = q.position_error;
      entry["rotation_error_deg"] = q.rotation_error_deg;
      if (q.inside95) entry["inside95"] = *q.inside95;
      if (q.enu_error) {
        entry["ground_error"] = q.enu_error->ground;
        entry["height_error"] = q.enu_error->height;
      }
      if (run.geo) {
        // null: the result has no "geo", so it is missing for the comparison on the globe.
        entry["geo"] = q.geo_error ? ordered_json{{"error_m", q.geo_error->distance},
                                                  {"ground_error_m", q.geo_error->ground},
                                                  {"height_error_m", q.geo_error->height}}
                                   : ordered_json(nullptr);
      }
    }
    per_query.push_back(entry);
  }
  return per_query;
}

// One run's entry of the report's "runs".
ordered_json RunToJson(const RunReport& run, const EvalReport& report) {
  ordered_json r;
  r["label"] = run.label;
  r["path"] = run.path.string();
  r["format"] = ResultFormatName(run.format);
  r["queries"] = run.queries;
  r["localized"] = run.localized;
  r["not_localized"] = run.not_localized;
  r["errors"] = run.errors;
  r["missing"] = run.missing;
  r["unknown_names"] = run.unknown_names;
  r["localized_share"] = run.queries ? double(run.localized) / run.queries : 0.0;
  r["position_error"] = QuartilesJson(run.position_error);
  r["rotation_error_deg"] = QuartilesJson(run.rotation_error_deg);
  if (run.enu_errors) {
    r["ground_error"] = QuartilesJson(run.ground_error);
    r["height_error"] = QuartilesJson(run.height_error);
  }
  ordered_json within = ordered_json::array();
  for (size_t t = 0; t < kThresholds.size(); ++t) {
    within.push_back({{"position", kThresholds[t].position},
                      {"rotation_deg", kThresholds[t].rotation_deg},
                      {"count", run.within[t]},
                      {"share", run.queries ? double(run.within[t]) / run.queries : 0.0}});
  }
  r["within"] = within;
  if (run.geo) {
    const GeoComparison& geo = *run.geo;
    r["geo"] = {{"compared", geo.compared},
                {"without_geo", geo.without_geo},
                {"error_m", QuartilesJson(geo.error)},
                {"ground_error_m", QuartilesJson(geo.ground_error)},
                {"height_error_m", QuartilesJson(geo.height_error)},
                {"within",
                 {{"distance_m", kGeoWithinMetres},
                  {"count", geo.within},
                  {"share", run.queries ? double(geo.within) / run.queries : 0.0}}}};
  }
  r["coverage95"] = {
      {"with_covariance", run.with_covariance},
      {"inside", run.inside95},
      {"share", run.with_covariance ? double(run.inside95) / run.with_covariance : 0.0}};
  if (const auto& rig = run.rig) {
    r["rig"] = {{"frames", rig->frames},
                {"localized", rig->localized},
                {"position_error", QuartilesJson(rig->position_error)},
                {"rotation_error_deg", QuartilesJson(rig->rotation_error_deg)}};
  }
  if (const auto& sequence = run.sequence) {
    r["sequence"] = {{"frames", sequence->frames},
                     {"tracked", sequence->tracked},
                     {"relocalized", sequence->relocalized},
                     {"lost", sequence->lost},
                     {"tracked_position_error", QuartilesJson(sequence->tracked_error)},
                     {"relocalized_position_error", QuartilesJson(sequence->relocalized_error)},
                     {"longest_without_pose", sequence->longest_without_pose},
                     {"with_pose_share", sequence->with_pose_share}};
  }
  r["timed_records"] = run.timed_records;
  if (run.times_ms) {
    ordered_json times;
    for (size_t s = 0; s < kStageNames.size(); ++s)
      times[kStageNames[s]] = TimeQuantilesJson((*run.times_ms)[s]);
    r["times_ms"] = times;
  } else {
    r["times_ms"] = nullptr;
  }
  r["per_query"] = PerQueryJson(run);
  if (run.recognition) {
    const RecognitionScores& scores = *run.recognition;
    ordered_json top = ordered_json::object();
    for (size_t k = 0; k < kRecognitionRanks.size(); ++k) {
      top["top" + std::to_string(kRecognitionRanks[k])] = {
          {"count", scores.hits[k]},
          {"share", scores.queries ? double(scores.hits[k]) / scores.queries : 0.0}};
    }
    r["recognition"] = {{"min_shared_points", report.recognition_min_shared},
                        {"queries", scores.queries},
                        {"with_right_image", scores.with_right_image},
                        {"top", top}};
  }
  return r;
}

}  // namespace

nlohmann::ordered_json ReportToJson(const EvalReport& report) {
  ordered_json json;
  json["tool"] = "cwloc-eval";
  json["version"] = kToolVersion;
  json["ground_truth"] = {{"path", report.ground_truth_path.string()}, {"queries", report.queries}};
  json["unit"] = report.Unit();
  json["scale"] = report.scale;
  json["scale_path"] =
      report.scale_path ? ordered_json(report.scale_path->string()) : ordered_json(nullptr);
  json["quantile_method"] = "linear";
  ordered_json thresholds = ordered_json::array();
  for (const Threshold& t : kThresholds)
    thresholds.push_back({{"position", t.position}, {"rotation_deg", t.rotation_deg}});
  json["thresholds"] = thresholds;
  if (report.index_path && report.georeference) {
    const Geodetic& origin = report.georeference->origin;
    json["index"] = {{"path", report.index_path->string()},
                     {"scale", report.georeference->scale},
                     {"origin",
                      {{"latitude_deg", origin.latitude_deg},
                       {"longitude_deg", origin.longitude_deg},
                       {"height_m", origin.height_m}}}};
  }
  if (report.geo_truth_path) {
    json["ground_truth_geo"] = {{"path", report.geo_truth_path->string()},
                                {"positions", report.geo_truth_positions},
                                {"within_m", kGeoWithinMetres}};
  }

  ordered_json runs = ordered_json::array();
  for (const RunReport& run : report.runs) runs.push_back(RunToJson(run, report));
  json["runs"] = runs;
  return json;
}

namespace {

// What the report compares, and in which unit.
std::string Preamble(const EvalReport& report) {
  std::ostringstream out;
  out << "cwloc-eval: " << report.queries << " ground-truth queries from "
      << report.ground_truth_path.string() << "\n";
  if (report.georeference) {
    out << "distances in metres (scale " << Format("%.10g", report.georeference->scale)
        << " from the georeference of index "
        << (report.index_path ? report.index_path->string() : std::string("?")) << ")\n";
  } else if (report.Metric()) {
    out << "distances in metres (scale " << Format("%.10g", report.scale) << " from "
        << report.scale_path->string() << ")\n";
  } else {
    out << "distances in model units (no --scale given); the thresholds below use the metre values "
           "as model units\n";
  }
  out << "errors: Q1 / median / Q3 over localized queries; shares: of all ground-truth queries\n\n";
  return out.str();
}

// Each run's localized share, errors and shares within the thresholds.
std::string MainTable(const EvalReport& report) {
  const char* unit = report.Metric() ? "m" : "units";
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> header = {
      "run", "localized", std::string("position error (") + unit + ")", "rotation error (deg)"};
  for (const Threshold& t : kThresholds) header.push_back(ThresholdName(t, unit));
  rows.push_back(header);
  for (const RunReport& run : report.runs) {
    std::vector<std::string> row = {
        run.label, std::to_string(run.localized) + "/" + std::to_string(run.queries),
        QuartileCell(run.position_error), QuartileCell(run.rotation_error_deg)};
    for (size_t t = 0; t < kThresholds.size(); ++t)
      row.push_back(Percent(run.within[t], run.queries));
    rows.push_back(row);
  }
  return Columns(rows);
}

// Per run: why queries are not localized, names not in the truth, a sequence's frames, rig
// frames, and the covariance's coverage.
std::string RunNotes(const EvalReport& report) {
  std::ostringstream out;
  // Why a query is not localized matters when comparing runs.
  for (const RunReport& run : report.runs) {
    if (run.not_localized + run.errors + run.missing > 0) {
      out << "  " << run.label << ": not localized " << run.not_localized << ", error records "
          << run.errors << ", missing from results " << run.missing << "\n";
    }
  }
  for (const RunReport& run : report.runs) {
    if (run.unknown_names > 0) {
      out << "  warning: " << run.label << ": " << run.unknown_names
          << " result(s) for names not in the ground truth (ignored)\n";
    }
  }

  // A sequence's frames by how they got their pose (docs/algorithm.md, "Sequences").
  for (const RunReport& run : report.runs) {
    if (!run.sequence) continue;
    const SequenceReport& s = *run.sequence;
    const auto median = [](const std::optional<Quartiles>& q) {
      return q ? Number(q->median) : std::string("-");
    };
    out << "  " << run.label << ": sequence of " << s.frames << " frames: " << s.tracked
        << " tracked, " << s.relocalized << " relocalized, " << s.lost << " lost; "
        << Percent(s.tracked + s.relocalized, s.frames) << " with a pose, at most "
        << s.longest_without_pose << " in a row without; median position error tracked "
        << median(s.tracked_error) << ", relocalized " << median(s.relocalized_error) << " ("
        << report.Unit() << ")\n";
  }

  // Rig frames by their reference cameras (docs/algorithm.md, "Rigs and multi-frame queries").
  for (const RunReport& run : report.runs) {
    if (!run.rig) continue;
    const RigReport& r = *run.rig;
    out << "  " << run.label << ": " << r.frames << " rig frames, " << r.localized
        << " localized; the reference camera's median position error "
        << (r.position_error ? Number(r.position_error->median) : std::string("-")) << " "
        << report.Unit() << ", rotation "
        << (r.rotation_error_deg ? Number(r.rotation_error_deg->median) : std::string("-"))
        << " deg (the table counts every image)\n";
  }

  // How often the truth lies where the covariance says it should (docs/algorithm.md).
  for (const RunReport& run : report.runs) {
    if (run.with_covariance == 0) continue;
    out << "  " << run.label << ": true position inside the 95 % ellipsoid: " << run.inside95 << "/"
        << run.with_covariance << " (" << Percent(run.inside95, run.with_covariance) << ")\n";
  }
  return out.str();
}

// Errors on the ground and in height, for runs against a georeferenced index.
std::string EnuTable(const EvalReport& report) {
  bool any_enu = false;
  for (const RunReport& run : report.runs) any_enu = any_enu || run.enu_errors;
  if (!any_enu) return "";
  std::ostringstream out;
  out << "\non the ground, in the index's east-north-up frame\n(horizontal and |vertical| "
         "distance of the camera centres, m; Q1 / median / Q3 over localized queries)\n";
  std::vector<std::vector<std::string>> enu_rows = {
      {"run", "ground error (m)", "height error (m)"}};
  for (const RunReport& run : report.runs) {
    if (!run.enu_errors) continue;
    enu_rows.push_back({run.label, QuartileCell(run.ground_error), QuartileCell(run.height_error)});
  }
  out << Columns(enu_rows);
  return out.str();
}

// The results' "geo" against the true positions on the globe (--gt-geo).
std::string GeoTable(const EvalReport& report) {
  bool any_geo = false;
  for (const RunReport& run : report.runs) any_geo = any_geo || run.geo.has_value();
  if (!any_geo) return "";
  std::ostringstream out;
  out << "\non the globe, against the true positions in "
      << (report.geo_truth_path ? report.geo_truth_path->string() : std::string("?"))
      << "\n(the results' \"geo\" in the local east-north-up frame at each true position, m; "
         "Q1 / median / Q3 over the compared queries; share: of all ground-truth queries)\n";
  std::vector<std::vector<std::string>> geo_rows = {
      {"run", "compared", "3D error (m)", "ground error (m)", "height error (m)",
       std::string("within ") + Format("%g", kGeoWithinMetres) + " m"}};
  for (const RunReport& run : report.runs) {
    if (!run.geo) continue;
    geo_rows.push_back(
        {run.label, std::to_string(run.geo->compared) + "/" + std::to_string(run.localized),
         QuartileCell(run.geo->error), QuartileCell(run.geo->ground_error),
         QuartileCell(run.geo->height_error), Percent(run.geo->within, run.queries)});
  }
  out << Columns(geo_rows);
  for (const RunReport& run : report.runs) {
    if (!run.geo || run.geo->without_geo == 0) continue;
    out << "  " << run.label << ": " << run.geo->without_geo
        << " localized result(s) without \"geo\" (a poses file, or an index without "
           "georeference): missing from this comparison\n";
  }
  return out.str();
}

// Location recognition's top-k shares (--model, --min-shared).
std::string RecognitionTable(const EvalReport& report) {
  if (report.recognition_min_shared <= 0) return "";
  std::ostringstream out;
  out << "\nlocation recognition: a ranked image is right when it sees >= "
      << report.recognition_min_shared
      << " of the query's ground-truth 3D points; shares of all ground-truth queries\n";
  std::vector<std::vector<std::string>> recognition_rows;
  std::vector<std::string> recognition_header = {"run", "queries with a right image"};
  for (int k : kRecognitionRanks) recognition_header.push_back("top-" + std::to_string(k));
  recognition_rows.push_back(recognition_header);
  for (const RunReport& run : report.runs) {
    if (!run.recognition) continue;
    std::vector<std::string> row = {run.label, std::to_string(run.recognition->with_right_image)};
    for (int hits : run.recognition->hits) row.push_back(Percent(hits, run.recognition->queries));
    recognition_rows.push_back(row);
  }
  out << Columns(recognition_rows);
  return out.str();
}

// The stages' times, for runs whose records carry them.
std::string TimesTable(const EvalReport& report) {
  bool any_times = false;
  for (const RunReport& run : report.runs) any_times = any_times || run.times_ms.has_value();
  if (!any_times) return "";
  std::ostringstream out;
  out << "\ntimes (ms), Q1 / median / Q3 / p90 over the result records that carry times_ms\n";
  std::vector<std::vector<std::string>> time_rows;
  std::vector<std::string> time_header = {"run", "records"};
  for (const char* stage : kStageNames) time_header.push_back(stage);
  time_rows.push_back(time_header);
  for (const RunReport& run : report.runs) {
    std::vector<std::string> row = {run.label, std::to_string(run.timed_records)};
    for (size_t s = 0; s < kStageNames.size(); ++s) {
      row.push_back(run.times_ms ? TimeCell((*run.times_ms)[s]) : "-");
    }
    time_rows.push_back(row);
  }
  out << Columns(time_rows);
  return out.str();
}

}  // namespace

std::string FormatTable(const EvalReport& report) {
  return Preamble(report) + MainTable(report) + RunNotes(report) + EnuTable(report) +
         GeoTable(report) + RecognitionTable(report) + TimesTable(report);
}

}  // namespace cwloc::eval
