#pragma once
/// \file
/// Numbers as the reports print them.
#include <cmath>

namespace mgrl {

/// Rounds to `decimals` places for JSON: dividing by an exact power of ten yields the double
/// nearest the decimal, so JSON shows 0.5679 rather than 0.5679000000000001. NaN and
/// infinities stay as they are (null in JSON).
inline double rounded(double value, int decimals) {
  if (!std::isfinite(value)) return value;
  const double scale = std::pow(10.0, decimals);
  return std::round(value * scale) / scale;
}

}  // namespace mgrl
