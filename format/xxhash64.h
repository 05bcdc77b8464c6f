#pragma once

#include <cstdint>
#include <span>
#include <string>

namespace cwloc {

// xxHash64 (XXH64, seed 0 by default) as specified by its author; the index stores one per
// section and one over the header so corruption is found without trusting any offset.
uint64_t XxHash64(std::span<const uint8_t> bytes, uint64_t seed = 0);

// A hash as 16 lower-case hex digits, the way messages and manifests print checksums.
std::string HashHex(uint64_t hash);

}  // namespace cwloc
