#pragma once

#include <cstddef>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace cwloc {

// Asks Linux to back the 2 MiB-aligned pages inside [data, data + bytes) with transparent huge
// pages (its default mode, "madvise", only does so when asked). Call it on memory not yet
// touched: a page is backed at its first write. One fault per 2 MiB instead of 512, and fewer
// TLB misses: on a virtual machine, where a fault is dear, gathering a 10.8M-view model's
// descriptors took a third of the time (docs/benchmarks.md, "Updates"). A hint: nothing happens
// where it is refused or unknown.
void AdviseHugePages(const void* data, size_t bytes);

// `rows`'s capacity made `count` elements, advised as above before anything is written to it.
template <typename T, typename Allocator>
void ReserveOnHugePages(std::vector<T, Allocator>* rows, size_t count) {
  if (!rows->empty() || rows->capacity() >= count) return;
  rows->reserve(count);
  AdviseHugePages(rows->data(), count * sizeof(T));
}

// A vector's allocator whose resize() leaves new elements of trivial type unwritten, so that the
// pages of a big array that nothing writes are never backed (`cwloc-index update` leaves the
// rows it reads in the parent index unwritten in the child's 1.4 GB of descriptors). Range
// inserts construct element by element with it: write through data() instead.
template <typename T>
struct UnwrittenAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UnwrittenAllocator<U>;
  };
  UnwrittenAllocator() = default;
  template <typename U>
  UnwrittenAllocator(const UnwrittenAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* element) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(element)) U;
  }
  template <typename U, typename... Args>
  void construct(U* element, Args&&... args) {
    ::new (static_cast<void*>(element)) U(std::forward<Args>(args)...);
  }
};

}  // namespace cwloc
