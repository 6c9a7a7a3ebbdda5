#pragma once
/// \file
/// A small, fast, portable random generator (xoshiro256** by Blackman and Vigna, seeded
/// with splitmix64) with its own uniform draws, so a seed gives the same numbers with every
/// compiler and standard library, and the state fits in a checkpoint.
#include <array>
#include <cstdint>

namespace mgrl {

class Rng {
 public:
  explicit Rng(std::uint64_t seed = 1) {
    std::uint64_t x = seed;
    for (std::uint64_t& word : s_) {
      x += 0x9e3779b97f4a7c15ULL;
      std::uint64_t z = x;
      z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
      z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
      word = z ^ (z >> 31);
    }
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform in [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [0, n) for n >= 1 (Lemire's multiply-shift; the bias is below 2^-32 for
  /// the sizes used here and the same on every platform).
  std::uint64_t below(std::uint64_t n) {
    __extension__ typedef unsigned __int128 Wide;
    return static_cast<std::uint64_t>((static_cast<Wide>(next()) * n) >> 64);
  }

  std::array<std::uint64_t, 4> state() const { return s_; }
  void setState(const std::array<std::uint64_t, 4>& s) { s_ = s; }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> s_{};
};

}  // namespace mgrl
