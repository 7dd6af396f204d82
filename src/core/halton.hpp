// The Halton sequence: a fixed low-discrepancy cover of the joint angles,
// used where deterministic starting guesses are needed (assembly.cpp,
// motion.cpp).
#pragma once

#include <array>

#include "loopfarm/core/types.hpp"

namespace loopfarm {

// One prime base per dimension (a joint angle), at most one per joint.
inline constexpr std::array<int, kMaxJoints> kHaltonBases{2, 3, 5, 7, 11, 13, 17, 19};

// Radical inverse of i in the given base: coordinate i of the Halton
// sequence in that base, in [0, 1).
inline double radical_inverse(int base, int i) {
  double inverse = 0.0;
  double scale = 1.0 / base;
  while (i > 0) {
    inverse += (i % base) * scale;
    i /= base;
    scale /= base;
  }
  return inverse;
}

}  // namespace loopfarm
