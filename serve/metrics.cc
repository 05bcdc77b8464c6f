#include "serve/metrics.h"

#include <algorithm>
#include <cstdio>

namespace cwloc {
namespace {

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.9g", value);
  return text;
}

}  // namespace

void Metrics::Histogram::Add(double seconds) {
  const size_t bucket =
      std::lower_bound(kBuckets.begin(), kBuckets.end(), seconds) - kBuckets.begin();
  if (bucket < kBuckets.size()) ++counts[bucket];
  ++count;
  sum += seconds;
}

void Metrics::CountRequest(const std::string& endpoint, int status, double seconds) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++requests_[{endpoint, status}];
  request_seconds_[endpoint].Add(seconds);
}

void Metrics::CountError(const std::string& kind) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++errors_[kind];
}

void Metrics::CountResult(bool localized, const StageTimes& times) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++(localized ? localized_ : not_localized_);
  ForEachField<StageTimes>([&](const auto& stage) {
    stage_seconds_[std::string(stage.info.name)].Add(times.*stage.member);
  });
}

void Metrics::WriteHistogram(const std::string& name, const std::string& labels,
                             const Histogram& histogram, std::string* out) {
  uint64_t cumulative = 0;
  for (size_t b = 0; b < kBuckets.size(); ++b) {
    cumulative += histogram.counts[b];
    *out += name + "_bucket{" + labels + ",le=\"" + Number(kBuckets[b]) + "\"} " +
            std::to_string(cumulative) + "\n";
  }
  *out += name + "_bucket{" + labels + ",le=\"+Inf\"} " + std::to_string(histogram.count) + "\n";
  *out += name + "_sum{" + labels + "} " + Number(histogram.sum) + "\n";
  *out += name + "_count{" + labels + "} " + std::to_string(histogram.count) + "\n";
}

std::string Metrics::Text(const std::vector<Gauge>& gauges) const {
  std::lock_guard<std::mutex> lock(mutex_);
  std::string out;
  out += "# HELP cwloc_requests_total HTTP requests answered, by endpoint and status.\n";
  out += "# TYPE cwloc_requests_total counter\n";
  for (const auto& [key, count] : requests_) {
    out += "cwloc_requests_total{endpoint=\"" + key.first + "\",status=\"" +
           std::to_string(key.second) + "\"} " + std::to_string(count) + "\n";
  }
  out += "# HELP cwloc_errors_total Requests refused, by kind.\n";
  out += "# TYPE cwloc_errors_total counter\n";
  for (const auto& [kind, count] : errors_)
    out += "cwloc_errors_total{kind=\"" + kind + "\"} " + std::to_string(count) + "\n";
  out += "# HELP cwloc_queries_total Queries run, by whether they localized.\n";
  out += "# TYPE cwloc_queries_total counter\n";
  out += "cwloc_queries_total{localized=\"true\"} " + std::to_string(localized_) + "\n";
  out += "cwloc_queries_total{localized=\"false\"} " + std::to_string(not_localized_) + "\n";
  out +=
      "# HELP cwloc_request_seconds Whole requests, from their last byte read to their "
      "answer, by endpoint.\n";
  out += "# TYPE cwloc_request_seconds histogram\n";
  for (const auto& [endpoint, histogram] : request_seconds_)
    WriteHistogram("cwloc_request_seconds", "endpoint=\"" + endpoint + "\"", histogram, &out);
  out += "# HELP cwloc_stage_seconds Each pipeline stage of the queries run.\n";
  out += "# TYPE cwloc_stage_seconds histogram\n";
  for (const auto& [stage, histogram] : stage_seconds_)
    WriteHistogram("cwloc_stage_seconds", "stage=\"" + stage + "\"", histogram, &out);
  for (const Gauge& gauge : gauges) {
    out += "# HELP " + gauge.name + " " + gauge.help + "\n";
    out += "# TYPE " + gauge.name + " gauge\n";
    out += gauge.name + " " + Number(gauge.value) + "\n";
  }
  return out;
}

}  // namespace cwloc
