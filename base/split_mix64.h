#pragma once

// SplitMix64 (Steele, Lea and Flood, OOPSLA 2014): the project's one seedable generator. Its
// output sequence is fixed by the algorithm, unlike std::mt19937 with std::shuffle or
// std::uniform_int_distribution, whose results differ between standard libraries; the same
// seed therefore gives the same index and the same poses on every platform.

#include <cstdint>
#include <span>
#include <utility>

namespace cwloc {

// The SplitMix64 output function: a bijective, well-mixed hash of one 64-bit word.
inline uint64_t MixBits64(uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : state_(seed) {}

  uint64_t Next() { return MixBits64(state_ += 0x9E3779B97F4A7C15ULL); }

  // Uniform in [0, n) by multiply-shift of the top 32 bits (Lemire); the bias, below n / 2^32,
  // is irrelevant for sampling.
  uint32_t Uniform(uint32_t n) { return static_cast<uint32_t>(((Next() >> 32) * n) >> 32); }

  // Fisher-Yates with Uniform(): the same permutation on every platform.
  template <typename T>
  void Shuffle(std::span<T> items) {
    for (size_t i = items.size(); i > 1; --i) {
      std::swap(items[i - 1], items[Uniform(static_cast<uint32_t>(i))]);
    }
  }

 private:
  uint64_t state_;
};

}  // namespace cwloc
