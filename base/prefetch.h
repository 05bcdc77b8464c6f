#pragma once

namespace cwloc {

// Starts loading the cache line holding `p` before it is read, so that independent random
// reads overlap instead of each waiting for memory. Only a hint; nothing on other compilers.
inline void Prefetch(const void* p) {
#if defined(__GNUC__) || defined(__clang__)
  __builtin_prefetch(p);
#else
  (void)p;
#endif
}

}  // namespace cwloc
