#include "format/xxhash64.h"

#include <algorithm>
#include <bit>
#include <cstring>

namespace cwloc {
namespace {

constexpr uint64_t kPrime1 = 0x9E3779B185EBCA87ULL;
constexpr uint64_t kPrime2 = 0xC2B2AE3D27D4EB4FULL;
constexpr uint64_t kPrime3 = 0x165667B19E3779F9ULL;
constexpr uint64_t kPrime4 = 0x85EBCA77C2B2AE63ULL;
constexpr uint64_t kPrime5 = 0x27D4EB2F165667C5ULL;

inline uint64_t RotateLeft(uint64_t x, int r) { return (x << r) | (x >> (64 - r)); }

// Little-endian loads, so the hash is the same on every host.
inline uint64_t Load64(const uint8_t* p) {
  if constexpr (std::endian::native == std::endian::little) {
    uint64_t v;
    std::memcpy(&v, p, 8);
    return v;
  }
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

inline uint32_t Load32(const uint8_t* p) {
  return uint32_t{p[0]} | (uint32_t{p[1]} << 8) | (uint32_t{p[2]} << 16) | (uint32_t{p[3]} << 24);
}

inline uint64_t Round(uint64_t acc, uint64_t input) {
  acc += input * kPrime2;
  return RotateLeft(acc, 31) * kPrime1;
}

inline uint64_t MergeRound(uint64_t acc, uint64_t value) {
  acc ^= Round(0, value);
  return acc * kPrime1 + kPrime4;
}

}  // namespace

std::string HashHex(uint64_t hash) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string hex(16, '0');
  for (int i = 15; i >= 0; --i, hash >>= 4) hex[i] = kDigits[hash & 15];
  return hex;
}

XxHash64Stream::XxHash64Stream(uint64_t seed)
    : seed_(seed), lanes_{seed + kPrime1 + kPrime2, seed + kPrime2, seed, seed - kPrime1} {}

void XxHash64Stream::Update(std::span<const uint8_t> bytes) {
  // Sizes are compared as remaining bytes, never as p + n <= end: an empty span may have a
  // null data pointer, and null + n is undefined.
  const uint8_t* p = bytes.data();
  size_t left = bytes.size();
  length_ += left;
  if (left == 0) return;
  if (buffered_ > 0) {
    const size_t take = std::min(left, sizeof(buffer_) - buffered_);
    std::memcpy(buffer_ + buffered_, p, take);
    buffered_ += take;
    p += take;
    left -= take;
    if (buffered_ < sizeof(buffer_)) return;
    Stripes(buffer_, sizeof(buffer_));
    buffered_ = 0;
  }
  const size_t whole = left / 32 * 32;
  if (whole > 0) Stripes(p, whole);
  if (left > whole) std::memcpy(buffer_, p + whole, left - whole);
  buffered_ = left - whole;
}

void XxHash64Stream::Stripes(const uint8_t* p, size_t size) {
  uint64_t v1 = lanes_[0], v2 = lanes_[1], v3 = lanes_[2], v4 = lanes_[3];
  for (const uint8_t* end = p + size; p != end; p += 32) {
    v1 = Round(v1, Load64(p));
    v2 = Round(v2, Load64(p + 8));
    v3 = Round(v3, Load64(p + 16));
    v4 = Round(v4, Load64(p + 24));
  }
  lanes_[0] = v1, lanes_[1] = v2, lanes_[2] = v3, lanes_[3] = v4;
}

uint64_t XxHash64Stream::Digest() const {
  uint64_t h;
  if (length_ >= 32) {
    const uint64_t v1 = lanes_[0], v2 = lanes_[1], v3 = lanes_[2], v4 = lanes_[3];
    h = RotateLeft(v1, 1) + RotateLeft(v2, 7) + RotateLeft(v3, 12) + RotateLeft(v4, 18);
    h = MergeRound(h, v1);
    h = MergeRound(h, v2);
    h = MergeRound(h, v3);
    h = MergeRound(h, v4);
  } else {
    h = seed_ + kPrime5;
  }
  h += length_;
  const uint8_t* p = buffer_;
  const uint8_t* const end = buffer_ + buffered_;
  for (; end - p >= 8; p += 8) h = RotateLeft(h ^ Round(0, Load64(p)), 27) * kPrime1 + kPrime4;
  if (end - p >= 4) {
    h = RotateLeft(h ^ (uint64_t{Load32(p)} * kPrime1), 23) * kPrime2 + kPrime3;
    p += 4;
  }
  for (; p < end; ++p) h = RotateLeft(h ^ (uint64_t{*p} * kPrime5), 11) * kPrime1;
  h ^= h >> 33;
  h *= kPrime2;
  h ^= h >> 29;
  h *= kPrime3;
  h ^= h >> 32;
  return h;
}

uint64_t XxHash64(std::span<const uint8_t> bytes, uint64_t seed) {
  XxHash64Stream stream(seed);
  stream.Update(bytes);
  return stream.Digest();
}

}  // namespace cwloc
