// An index file as it reaches a device: opened (the header, the section table and every
// section's bounds are checked), then used by the localizer without verification, as
// cwloc-localize does by default, on queries made of the index's own descriptors (with the
// position and gravity priors when it is georeferenced), then verified as `cwloc-index verify`
// does. Mutated header or table bytes mostly break their checksums, so each input is opened a
// second time with both checksums made right, to reach the checks behind them.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "base/error.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "fuzz/fuzz_file.h"
#include "localizer/localizer.h"

namespace cwloc {
namespace {

// Up to 48 features: the first kd-forest rows' descriptors (views', or decoded point codes) at
// made-up pixels.
Query QueryFromIndex(const Index& index) {
  Query query;
  query.name = "fuzz";
  query.camera.model_id = CameraModelId::kSimplePinhole;
  query.camera.width = 1024;
  query.camera.height = 768;
  query.camera.params = {900, 512, 384};
  const size_t features = std::min<size_t>(index.num_rows(), 48);
  query.descriptors.resize(features * kDescriptorBytes);
  uint8_t scratch[kDescriptorBytes];
  for (size_t i = 0; i < features; ++i) {
    std::copy_n(index.RowDescriptor(uint32_t(i), scratch), kDescriptorBytes,
                &query.descriptors[i * kDescriptorBytes]);
  }
  for (size_t i = 0; i < features; ++i) {
    query.keypoints.push_back(float(37 * i % 1024));
    query.keypoints.push_back(float(53 * i % 768));
  }
  return query;
}

void UseIndex(const std::filesystem::path& path) {
  try {
    const Index index = Index::Open(path);
    const Localizer localizer(index);
    Query query = QueryFromIndex(index);
    if (query.NumFeatures() > 0) {
      // Made-up pixels fit no pose: a few RANSAC rounds reach every stage without spending
      // each run in RANSAC, which reads no index data.
      LocalizerOptions options;
      options.pose.ransac.min_iterations = 10;
      options.pose.ransac.max_iterations = 20;
      try {
        localizer.Localize(query, options);
        if (localizer.geo()) {
          const Geodetic origin = localizer.geo()->frame().georeference().origin;
          query.position_prior =
              PositionPrior{{origin.latitude_deg, origin.longitude_deg, {}, 500.0}};
          query.gravity = std::array<double, 3>{0, 1, 0};
          localizer.Localize(query, options);
        }
      } catch (const InputError&) {
      }
    }
    index.file().VerifyChecksums();
    index.Validate();
  } catch (const InputError&) {
  }
}

// The bytes with the header's and the section table's checksums recomputed, where the header
// says where the table is.
std::vector<uint8_t> WithHeaderChecksumsRight(std::span<const uint8_t> bytes) {
  std::vector<uint8_t> fixed(bytes.begin(), bytes.end());
  if (fixed.size() < sizeof(FileHeader)) return fixed;
  FileHeader header;
  std::memcpy(&header, fixed.data(), sizeof header);
  const uint64_t table_size = uint64_t{header.section_count} * sizeof(SectionEntry);
  if (header.section_table_offset <= fixed.size() &&
      table_size <= fixed.size() - header.section_table_offset) {
    header.section_table_checksum = XxHash64(
        std::span(fixed).subspan(header.section_table_offset, static_cast<size_t>(table_size)));
  }
  header.header_checksum = XxHash64(
      std::span(reinterpret_cast<const uint8_t*>(&header), offsetof(FileHeader, header_checksum)));
  std::memcpy(fixed.data(), &header, sizeof header);
  return fixed;
}

}  // namespace
}  // namespace cwloc

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cwloc;
  UseIndex(fuzz::WriteFile("index.cwl", data, size));
  const std::vector<uint8_t> fixed = WithHeaderChecksumsRight({data, size});
  if (!std::equal(fixed.begin(), fixed.end(), data)) UseIndex(fuzz::WriteFile("index.cwl", fixed));
  return 0;
}
