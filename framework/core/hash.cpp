#include "mgrl/core/hash.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include <fmt/format.h>

namespace mgrl {
namespace {

// XXH64 (Yann Collet, xxhash.com, spec in doc/xxhash_spec.md). Chosen over FNV-1a because it
// reads 8 bytes per step in four independent lanes, so it runs near memory speed, and
// because any xxhash binding can check the digests mgrl writes.
constexpr std::uint64_t kPrime1 = 0x9E3779B185EBCA87ULL;
constexpr std::uint64_t kPrime2 = 0xC2B2AE3D27D4EB4FULL;
constexpr std::uint64_t kPrime3 = 0x165667B19E3779F9ULL;
constexpr std::uint64_t kPrime4 = 0x85EBCA77C2B2AE63ULL;
constexpr std::uint64_t kPrime5 = 0x27D4EB2F165667C5ULL;

// Explicit little-endian reads, so the digest does not depend on the host's byte order;
// GCC turns these loops into single loads on little-endian machines.
std::uint64_t read64(const unsigned char* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::uint32_t read32(const unsigned char* p) {
  std::uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

std::uint64_t round(std::uint64_t acc, std::uint64_t input) {
  acc += input * kPrime2;
  acc = std::rotl(acc, 31);
  return acc * kPrime1;
}

std::uint64_t mergeRound(std::uint64_t acc, std::uint64_t lane) {
  acc ^= round(0, lane);
  return acc * kPrime1 + kPrime4;
}

inline __attribute__((always_inline)) void consumeStripe(std::uint64_t* acc, const unsigned char* p) {
  acc[0] = round(acc[0], read64(p));
  acc[1] = round(acc[1], read64(p + 8));
  acc[2] = round(acc[2], read64(p + 16));
  acc[3] = round(acc[3], read64(p + 24));
}

}  // namespace

Hasher::Hasher() : acc_{kPrime1 + kPrime2, kPrime2, 0, 0 - kPrime1} {}

Hasher& Hasher::updateBytes(std::string_view bytes) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  std::size_t n = bytes.size();
  totalLength_ += n;
  if (buffered_ > 0) {
    const std::size_t take = std::min(n, kStripe - buffered_);
    std::memcpy(buffer_.data() + buffered_, p, take);
    buffered_ += take;
    p += take;
    n -= take;
    if (buffered_ < kStripe) return *this;
    consumeStripe(acc_, buffer_.data());
    buffered_ = 0;
  }
  // Local copies let the compiler keep the four lanes in registers.
  std::uint64_t acc[4] = {acc_[0], acc_[1], acc_[2], acc_[3]};
  for (; n >= kStripe; p += kStripe, n -= kStripe) consumeStripe(acc, p);
  std::memcpy(acc_, acc, sizeof acc);
  if (n > 0) std::memcpy(buffer_.data(), p, n);
  buffered_ = n;
  return *this;
}

Hasher& Hasher::update(std::string_view text) {
  update(static_cast<std::int64_t>(text.size()));
  return updateBytes(text);
}

Hasher& Hasher::update(std::int64_t value) {
  const auto bits = static_cast<std::uint64_t>(value);
  char bytes[8];
  for (int i = 0; i < 8; ++i) bytes[i] = static_cast<char>((bits >> (8 * i)) & 0xff);
  return updateBytes(std::string_view(bytes, sizeof bytes));
}

Hasher& Hasher::update(double value) {
  return update(std::bit_cast<std::int64_t>(value));
}

std::uint64_t Hasher::value() const {
  std::uint64_t h;
  if (totalLength_ >= kStripe) {
    h = std::rotl(acc_[0], 1) + std::rotl(acc_[1], 7) + std::rotl(acc_[2], 12) + std::rotl(acc_[3], 18);
    for (std::uint64_t lane : acc_) h = mergeRound(h, lane);
  } else {
    h = kPrime5;  // seed 0 + prime 5
  }
  h += totalLength_;
  const unsigned char* p = buffer_.data();
  std::size_t n = buffered_;
  for (; n >= 8; p += 8, n -= 8) h = std::rotl(h ^ round(0, read64(p)), 27) * kPrime1 + kPrime4;
  if (n >= 4) {
    h = std::rotl(h ^ (static_cast<std::uint64_t>(read32(p)) * kPrime1), 23) * kPrime2 + kPrime3;
    p += 4;
    n -= 4;
  }
  for (; n > 0; ++p, --n) h = std::rotl(h ^ (*p * kPrime5), 11) * kPrime1;
  // Final avalanche: every input bit affects every output bit.
  h ^= h >> 33;
  h *= kPrime2;
  h ^= h >> 29;
  h *= kPrime3;
  h ^= h >> 32;
  return h;
}

std::string Hasher::hex() const { return hexDigest(value()); }

std::uint64_t hashBytes(std::string_view bytes) { return Hasher().updateBytes(bytes).value(); }

std::string hexDigest(std::uint64_t value) { return fmt::format("{:016x}", value); }

}  // namespace mgrl
