// Counts every heap allocation the test program makes, so that a test can show
// that a hot path allocates nothing. Include in exactly one file per test
// program: it replaces the global operator new and, on glibc, malloc itself.
//
// Both are needed: operator new alone misses Eigen, whose dynamic-size
// matrices allocate with std::malloc (Eigen/src/Core/util/Memory.h), so a
// regression from the fixed-capacity types of types.hpp to MatrixXd would
// pass unseen. A malloc defined in the executable takes the place of libc's
// for the whole process (ELF symbol interposition), libstdc++'s operator new
// included; it forwards to glibc's own allocator.
//
// AddressSanitizer replaces malloc and operator new itself and calls malloc
// before its shadow memory exists, where the counter's instrumented increment
// would crash: under it nothing is replaced, kCountsAllocations is false, and
// the tests that count skip (scripts/test.sh --sanitize). gcc says so with
// __SANITIZE_ADDRESS__, clang (14) only through __has_feature.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define LOOPFARM_UNDER_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define LOOPFARM_UNDER_ASAN 1
#endif
#endif

#include <atomic>
#include <cstdlib>
#include <new>

namespace loopfarm::testing {
inline std::atomic<long> g_allocations{0};
inline long allocations() { return g_allocations.load(); }
#if defined(LOOPFARM_UNDER_ASAN)
inline constexpr bool kCountsAllocations = false;
#else
inline constexpr bool kCountsAllocations = true;
#endif
}  // namespace loopfarm::testing

#if !defined(LOOPFARM_UNDER_ASAN)
#if defined(__GLIBC__)
extern "C" {
void* __libc_malloc(std::size_t size);  // glibc's allocator, under its own name
void* malloc(std::size_t size) {
  ++loopfarm::testing::g_allocations;
  return __libc_malloc(size);
}
}
#endif

void* operator new(std::size_t size) {
  ++loopfarm::testing::g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// Not inlined: GCC would otherwise see free() meet a pointer from operator new
// at the call site and warn (-Wmismatched-new-delete), although the pair matches.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#endif  // !LOOPFARM_UNDER_ASAN
