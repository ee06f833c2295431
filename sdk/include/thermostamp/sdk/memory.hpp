#pragma once
// Arrays over a whole part (per element, per node) for the hot loops of
// plugins.
//
// large_vector<T> is a std::vector whose storage, from 1 MiB up, is
// aligned to 2 MiB and offered to the operating system for transparent
// huge pages (Linux madvise(MADV_HUGEPAGE)). A loop that streams through
// many such arrays at once then needs one translation (TLB) entry per 2 MiB
// of each instead of one per 4 KiB. Where the system gives huge pages only
// on request (/sys/kernel/mm/transparent_hugepage/enabled says
// `madvise`), this is that request; where it gives them always or never,
// nothing changes. Smaller arrays are allocated as by std::allocator. The
// contents, and so the results, do not depend on it.
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace ts::sdk {

inline constexpr std::size_t kLargeArrayBytes = std::size_t{1} << 20;
inline constexpr std::size_t kHugePageBytes = std::size_t{2} << 20;

template <class T>
struct large_allocator {
  using value_type = T;
  large_allocator() = default;
  template <class U>
  large_allocator(const large_allocator<U>&) noexcept {}
  T* allocate(std::size_t n) {
    if (n > static_cast<std::size_t>(-1) / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < kLargeArrayBytes) return std::allocator<T>().allocate(n);
    const std::size_t rounded = (bytes + kHugePageBytes - 1) / kHugePageBytes * kHugePageBytes;
    void* p = std::aligned_alloc(kHugePageBytes, rounded);
    if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    madvise(p, rounded, MADV_HUGEPAGE);  // a request: failure only means small pages
#endif
    return static_cast<T*>(p);
  }
  void deallocate(T* p, std::size_t n) noexcept {
    if (n * sizeof(T) < kLargeArrayBytes)
      std::allocator<T>().deallocate(p, n);
    else
      std::free(p);
  }
  template <class U>
  bool operator==(const large_allocator<U>&) const noexcept {
    return true;
  }
};

template <class T>
using large_vector = std::vector<T, large_allocator<T>>;

}  // namespace ts::sdk
