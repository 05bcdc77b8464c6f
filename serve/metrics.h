#pragma once

// The server's counters for GET /metrics, in Prometheus' text format (docs/serve.md,
// "Metrics"): requests by endpoint and status, errors by kind, the latency of whole requests
// and of each pipeline stage as histograms, and gauges the caller reads when asked.

#include <array>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "results/localization_result.h"

namespace cwloc {

class Metrics {
 public:
  struct Gauge {
    std::string name;
    std::string help;
    double value = 0;
  };

  void CountRequest(const std::string& endpoint, int status, double seconds);
  void CountError(const std::string& kind);  // bad_request, overloaded, expired, ...
  void CountResult(bool localized, const StageTimes& times);

  // The text of GET /metrics, with these gauges (queue depth, busy workers, sessions, ...).
  std::string Text(const std::vector<Gauge>& gauges) const;

 private:
  // Upper bounds in seconds: a cached-feature query takes milliseconds, a 6000-feature photo
  // about 0.4 s, an overloaded queue seconds.
  static constexpr std::array<double, 14> kBuckets = {0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                      0.25,  0.5,    1,     2.5,  5,     10,   30};
  struct Histogram {
    std::array<uint64_t, kBuckets.size()> counts{};  // per bucket, not cumulative
    uint64_t count = 0;
    double sum = 0;
    void Add(double seconds);
  };
  static void WriteHistogram(const std::string& name, const std::string& labels,
                             const Histogram& histogram, std::string* out);

  mutable std::mutex mutex_;
  std::map<std::pair<std::string, int>, uint64_t> requests_;
  std::map<std::string, uint64_t> errors_;
  std::map<std::string, Histogram> request_seconds_;  // by endpoint
  std::map<std::string, Histogram> stage_seconds_;    // by stage
  uint64_t localized_ = 0;
  uint64_t not_localized_ = 0;
};

}  // namespace cwloc
