#include "serve/index_registry.h"

#include <filesystem>
#include <set>
#include <utility>

#include "base/error.h"

namespace cwloc {

IndexSpec ParseIndexSpec(const std::string& text) {
  const size_t equals = text.find('=');
  IndexSpec spec;
  if (equals == std::string::npos) {
    spec.path = text;
    spec.name = std::filesystem::path(text).stem().string();
  } else {
    spec.name = text.substr(0, equals);
    spec.path = text.substr(equals + 1);
  }
  if (spec.path.empty()) throw InputError("--index '" + text + "': no file");
  if (spec.name.empty() ||
      spec.name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                  "0123456789_.-") != std::string::npos) {
    throw InputError("--index '" + text +
                     "': a name is letters, digits, '_', '.' and '-' (give NAME=FILE)");
  }
  return spec;
}

ServedIndex::ServedIndex(IndexSpec spec_in, bool verify)
    : spec(std::move(spec_in)), index(Index::Open(spec.path)), localizer(index) {
  if (verify) {
    index.file().VerifyChecksums();
    index.Validate();
  }
}

nlohmann::ordered_json ServedIndex::Info() const {
  nlohmann::ordered_json info;
  info["name"] = spec.name;
  info["path"] = spec.path;
  info["format_version"] = std::to_string(index.file().header().format_major) + "." +
                           std::to_string(index.file().header().format_minor);
  info["images"] = index.images().size();
  info["points"] = index.num_points();
  info["views"] = index.num_views();
  info["georeferenced"] = index.georeference() != nullptr;
  if (const IndexGeoreference* georeference = index.georeference()) {
    info["origin"] = {{"latitude_deg", georeference->origin_latitude_deg},
                      {"longitude_deg", georeference->origin_longitude_deg},
                      {"height_m", georeference->origin_height_m}};
  }
  info["generation"] = generation;
  const nlohmann::json manifest =
      nlohmann::json::parse(index.manifest_json(), nullptr, /*allow_exceptions=*/false);
  info["manifest"] = manifest.is_discarded() ? nlohmann::json() : manifest;
  return info;
}

IndexRegistry::IndexRegistry(std::vector<IndexSpec> specs, bool verify)
    : specs_(std::move(specs)), verify_(verify) {
  if (specs_.empty()) throw InputError("give at least one --index");
  std::set<std::string> names;
  for (const IndexSpec& spec : specs_) {
    if (!names.insert(spec.name).second)
      throw InputError("--index: two indexes named '" + spec.name + "' (give NAME=FILE)");
  }
  set_ = std::make_shared<const Set>(Open(specs_, verify_, 0));
}

IndexRegistry::Set IndexRegistry::Open(const std::vector<IndexSpec>& specs, bool verify,
                                       uint64_t generation) {
  Set set;
  for (const IndexSpec& spec : specs) {
    auto served = std::make_shared<ServedIndex>(spec, verify);
    served->generation = generation;
    set.push_back(std::move(served));
  }
  return set;
}

std::shared_ptr<const ServedIndex> IndexRegistry::Find(const std::string& name) const {
  std::shared_ptr<const Set> set;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    set = set_;
  }
  if (name.empty()) return set->front();
  for (const auto& served : *set) {
    if (served->spec.name == name) return served;
  }
  return nullptr;
}

std::vector<std::shared_ptr<const ServedIndex>> IndexRegistry::All() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return *set_;
}

void IndexRegistry::Reload() {
  std::lock_guard<std::mutex> one_at_a_time(reload_mutex_);
  auto set = std::make_shared<const Set>(Open(specs_, verify_, generation() + 1));
  std::lock_guard<std::mutex> lock(mutex_);
  set_ = std::move(set);
}

uint64_t IndexRegistry::generation() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return set_->front()->generation;  // every index of a set was opened by the same reload
}

}  // namespace cwloc
