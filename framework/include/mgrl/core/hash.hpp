#pragma once
/// \file
/// A fast 64-bit content hash for cache keys and file checksums (not for security: anyone
/// can forge a collision). The digest is XXH64 with seed 0 over the bytes fed in, so a
/// bundle's hashes can be checked outside mgrl, e.g. in Python with
/// `xxhash.xxh64(open(f, "rb").read()).hexdigest()`. Deterministic across runs, compilers
/// and machines: numbers are fed in as explicit little-endian bytes.

#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace mgrl {

/// Accumulates a byte stream and reports its XXH64 digest (seed 0). Splitting the stream
/// differently across updateBytes() calls gives the same digest.
///
/// The typed updates append a fixed encoding, with no type tag, so a key is only as
/// unambiguous as the sequence of fields it hashes:
/// - `update(std::int64_t)` (and any other integer, converted to it): 8 bytes, two's
///   complement, little-endian;
/// - `update(double)`: the 8 bytes of the IEEE-754 bit pattern, little-endian (so 0.0 and
///   -0.0 differ, and NaNs hash by payload);
/// - `update(std::string_view)`: its length as `update(std::int64_t)`, then its bytes, so
///   ("ab", "c") and ("a", "bc") differ.
///
/// Throughput is about 2.5 GB/s for large updates on this project's 2-core machine (-O2);
/// value() does not reset the stream.
class Hasher {
 public:
  Hasher();

  /// Appends raw bytes, with no length prefix.
  Hasher& updateBytes(std::string_view bytes);
  /// Appends a length-prefixed string (see the class comment).
  Hasher& update(std::string_view text);
  /// Appends 8 little-endian bytes.
  Hasher& update(std::int64_t value);
  /// Appends the 8 little-endian bytes of the bit pattern.
  Hasher& update(double value);
  /// Any other integer type, as `update(std::int64_t)` (unsigned values wrap into int64).
  template <std::integral I>
  Hasher& update(I value) {
    return update(static_cast<std::int64_t>(value));
  }

  /// The digest of everything appended so far.
  std::uint64_t value() const;
  /// value() as 16 lowercase hex digits.
  std::string hex() const;

 private:
  static constexpr std::size_t kStripe = 32;
  std::uint64_t acc_[4];
  std::uint64_t totalLength_ = 0;
  std::array<unsigned char, kStripe> buffer_{};  ///< bytes not yet filling a stripe
  std::size_t buffered_ = 0;
};

/// XXH64 (seed 0) of `bytes`: `Hasher().updateBytes(bytes).value()`.
std::uint64_t hashBytes(std::string_view bytes);

/// `value` as 16 lowercase hex digits.
std::string hexDigest(std::uint64_t value);

}  // namespace mgrl
