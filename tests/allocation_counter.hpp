// Counts every heap allocation the test program makes, so that a test can show
// that a hot path allocates nothing. Include in exactly one file per test
// program: it replaces the global operator new.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

namespace loopfarm::testing {
inline std::atomic<long> g_allocations{0};
inline long allocations() { return g_allocations.load(); }
}  // namespace loopfarm::testing

void* operator new(std::size_t size) {
  ++loopfarm::testing::g_allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
// Not inlined: GCC would otherwise see free() meet a pointer from operator new
// at the call site and warn (-Wmismatched-new-delete), although the pair matches.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
