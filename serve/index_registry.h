#pragma once

// The indexes a server answers from, by name. A reload opens every file again and swaps the
// whole set at once: a request keeps the index it started with until it ends, the next one
// gets the new set, and a file that fails to open leaves the old set in place.

#include <cstdint>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "format/index.h"
#include "localizer/localizer.h"

namespace cwloc {

struct IndexSpec {
  std::string name;
  std::string path;
};

// "FILE" (named by its file name without extension) or "NAME=FILE"; throws InputError.
IndexSpec ParseIndexSpec(const std::string& text);

// One opened index. Never moved: the localizer refers to the index.
struct ServedIndex {
  ServedIndex(IndexSpec spec_in, bool verify);
  ServedIndex(const ServedIndex&) = delete;
  ServedIndex& operator=(const ServedIndex&) = delete;

  // Its manifest and counts, as GET /v1/info lists them.
  nlohmann::ordered_json Info() const;

  IndexSpec spec;
  Index index;
  Localizer localizer;
  uint64_t generation = 0;  // how many reloads made it
};

class IndexRegistry {
 public:
  // Opens every index; throws InputError naming the file. The first is the default.
  IndexRegistry(std::vector<IndexSpec> specs, bool verify);

  // The index of this name, or the default for an empty name; null when there is none.
  std::shared_ptr<const ServedIndex> Find(const std::string& name) const;
  std::vector<std::shared_ptr<const ServedIndex>> All() const;

  // Opens every file again and swaps them in at once; throws InputError naming the file that
  // failed, and then keeps the indexes it had.
  void Reload();
  uint64_t generation() const;

 private:
  using Set = std::vector<std::shared_ptr<const ServedIndex>>;
  static Set Open(const std::vector<IndexSpec>& specs, bool verify, uint64_t generation);

  const std::vector<IndexSpec> specs_;
  const bool verify_;
  mutable std::mutex mutex_;
  std::shared_ptr<const Set> set_;
  std::mutex reload_mutex_;  // one reload at a time
};

}  // namespace cwloc
