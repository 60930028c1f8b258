// splitmix64's finalizer (Steele, Lea and Flood, "Fast splittable pseudorandom number generators",
// OOPSLA 2014): a 64-bit number mixed so that each input bit moves about half the output bits.
// The engine's counter-based randomness (particles) and the colouring's scrambled start
// (constraint_graph.cpp) both draw from it
#pragma once

#include <cstdint>

namespace rtp::detail {

inline std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

}  // namespace rtp::detail
