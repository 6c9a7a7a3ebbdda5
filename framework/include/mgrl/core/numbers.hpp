#pragma once
/// \file
/// Numbers as the reports print them: rounded for JSON, and for people.
#include <cmath>
#include <string>

#include <fmt/format.h>

namespace mgrl {

/// Rounds to `decimals` places for JSON: dividing by an exact power of ten yields the double
/// nearest the decimal, so JSON shows 0.5679 rather than 0.5679000000000001. NaN and
/// infinities stay as they are (null in JSON).
inline double rounded(double value, int decimals) {
  if (!std::isfinite(value)) return value;
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

/// "4.17 M", "850.0 k": counts and rates for people (with a trailing space for units).
inline std::string humanCount(double n) {
  if (n >= 1e9) return fmt::format("{:.2f} G", n / 1e9);
  if (n >= 1e6) return fmt::format("{:.2f} M", n / 1e6);
  if (n >= 1e3) return fmt::format("{:.1f} k", n / 1e3);
  return fmt::format("{:.0f} ", n);
}

/// "88.3 MB", "47.40 GB".
inline std::string humanBytes(double bytes) {
  if (bytes >= 1e9) return fmt::format("{:.2f} GB", bytes / 1e9);
  return fmt::format("{:.1f} MB", bytes / 1e6);
}

/// A duration for people: "12.31 s", "4.2 ms", "0.3 ms" (never "0.00 s").
inline std::string humanSeconds(double seconds) {
  if (seconds >= 0.1) return fmt::format("{:.2f} s", seconds);
  if (seconds >= 0.001) return fmt::format("{:.1f} ms", seconds * 1e3);
  return fmt::format("{:.2f} ms", seconds * 1e3);
}

}  // namespace mgrl
