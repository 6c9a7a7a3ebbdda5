#pragma once
// Whether this test binary runs under AddressSanitizer (scripts/fuzz.sh's build-sanitize/):
// there, timing and memory limits do not hold, and the slowest quality tests use fewer
// trials (the checks are the same; the figures are deterministic per build).

namespace mgrl::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kAddressSanitizer = true;
#else
inline constexpr bool kAddressSanitizer = false;
#endif
#else
inline constexpr bool kAddressSanitizer = false;
#endif

}  // namespace mgrl::test
