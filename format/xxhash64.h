#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace cwloc {

// xxHash64 (XXH64, seed 0 by default) as specified by its author; the index stores one per
// section and one over the header so corruption is found without trusting any offset.
uint64_t XxHash64(std::span<const uint8_t> bytes, uint64_t seed = 0);

// The same hash of bytes given in pieces: Digest() after Update(a), Update(b) is XxHash64 of a
// followed by b, for a section written from several places or a file read in chunks.
class XxHash64Stream {
 public:
  explicit XxHash64Stream(uint64_t seed = 0);
  void Update(std::span<const uint8_t> bytes);
  uint64_t Digest() const;

 private:
  void Stripes(const uint8_t* p, size_t size);  // size: a multiple of 32

  uint64_t seed_;
  uint64_t lanes_[4];
  uint64_t length_ = 0;
  uint8_t buffer_[32];  // the bytes after the last whole 32-byte stripe
  size_t buffered_ = 0;
};

// A hash as 16 lower-case hex digits, the way messages and manifests print checksums.
std::string HashHex(uint64_t hash);

}  // namespace cwloc
