#pragma once
/// \file
/// An allocator for the big tables (Q tables, tabulated grid models): blocks of 2 MB and
/// more are mapped 2 MB-aligned and marked for transparent huge pages (madvise), so that
/// touching a 10 MB table takes a handful of page faults instead of thousands, and random
/// access over hundreds of megabytes (Q-learning's transitions) misses the TLB far less.
/// Smaller blocks come from operator new. Contents are as std::allocator leaves them; the
/// kernel ignores the advice where huge pages are off, and nothing else changes.
#include <cstddef>
#include <limits>
#include <new>

namespace mgrl {

namespace huge_pages {
/// Blocks of at least this many bytes are mapped (and rounded up to a multiple of it).
inline constexpr std::size_t kHugePage = std::size_t{2} << 20;
/// A zeroed, 2 MB-aligned mapping of `bytes` rounded up to kHugePage; throws
/// std::bad_alloc when the system refuses.
void* map(std::size_t bytes);
void unmap(void* p, std::size_t bytes) noexcept;
}  // namespace huge_pages

template <class T>
struct HugePageAllocator {
  using value_type = T;

  HugePageAllocator() noexcept = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) noexcept {}

  T* allocate(std::size_t n) {
    if (n > std::numeric_limits<std::size_t>::max() / sizeof(T)) throw std::bad_array_new_length();
    const std::size_t bytes = n * sizeof(T);
    if (bytes < huge_pages::kHugePage) return static_cast<T*>(::operator new (bytes, std::align_val_t{alignof(T)}));
    return static_cast<T*>(huge_pages::map(bytes));
  }
  void deallocate(T* p, std::size_t n) noexcept {
    const std::size_t bytes = n * sizeof(T);
    if (bytes < huge_pages::kHugePage)
      ::operator delete (p, std::align_val_t{alignof(T)});
    else
      huge_pages::unmap(p, bytes);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const noexcept {
    return true;
  }
};

}  // namespace mgrl
