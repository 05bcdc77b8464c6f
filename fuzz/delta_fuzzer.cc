// A delta as it reaches a device: the input is a parent index and a delta (u32 little-endian
// parent length, the parent's bytes, then the delta's), and `cwloc-index apply` runs on them.
// Mutations mostly break checksums, so each input is applied a second time with the delta's
// section, table and header checksums made right and its parent checksum and size set to the
// parent's, to reach the checks behind them: runs, rows, counts and the kd-forest update.
#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

#include "base/error.h"
#include "delta/apply_delta.h"
#include "format/xxhash64.h"
#include "fuzz/fuzz_file.h"

namespace cwloc {
namespace {

// The delta with its parent named as `parent`'s header says and every checksum right.
std::vector<uint8_t> Repaired(std::span<const uint8_t> delta, std::span<const uint8_t> parent) {
  std::vector<uint8_t> bytes(delta.begin(), delta.end());
  if (bytes.size() < sizeof(FileHeader) || parent.size() < sizeof(FileHeader)) return bytes;
  FileHeader header, parent_header;
  std::memcpy(&header, bytes.data(), sizeof(header));
  std::memcpy(&parent_header, parent.data(), sizeof(parent_header));
  const uint64_t table = header.section_table_offset;
  const uint64_t count = header.section_count;
  if (table > bytes.size() || count > (bytes.size() - table) / sizeof(SectionEntry)) return bytes;
  for (uint64_t i = 0; i < count; ++i) {
    SectionEntry entry;
    std::memcpy(&entry, &bytes[table + i * sizeof(entry)], sizeof(entry));
    if (entry.tag != delta_section::kHeader || entry.offset > bytes.size() ||
        entry.size > bytes.size() - entry.offset || entry.size < sizeof(DeltaHeader))
      continue;
    DeltaHeader dhdr;
    std::memcpy(&dhdr, &bytes[entry.offset], sizeof(dhdr));
    dhdr.parent_checksum = parent_header.header_checksum;
    dhdr.parent_file_size = parent_header.file_size;
    std::memcpy(&bytes[entry.offset], &dhdr, sizeof(dhdr));
  }
  header.file_size = bytes.size();
  std::memcpy(bytes.data(), &header, sizeof(header));
  RecomputeChecksums(bytes);
  return bytes;
}

void Apply(std::span<const uint8_t> parent, std::span<const uint8_t> delta) {
  const std::filesystem::path parent_path = fuzz::WriteFile("parent.cwl", parent);
  const std::filesystem::path delta_path = fuzz::WriteFile("change.cwld", delta);
  const std::filesystem::path output = fuzz::ProcessFolder() / "child.cwl";
  try {
    ApplyDelta(parent_path, delta_path, output, 1);
  } catch (const InputError&) {
  }
  std::error_code ignored;
  std::filesystem::remove(output, ignored);
}

}  // namespace
}  // namespace cwloc

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 4) return 0;
  uint32_t parent_size;
  std::memcpy(&parent_size, data, 4);
  if (parent_size > size - 4) return 0;
  const std::span<const uint8_t> parent(data + 4, parent_size);
  const std::span<const uint8_t> delta(data + 4 + parent_size, size - 4 - parent_size);
  cwloc::Apply(parent, delta);
  cwloc::Apply(parent, cwloc::Repaired(delta, parent));
  return 0;
}
