#pragma once
/// \file
/// Counts in the text outputs read naturally: "1 file", "2 files".
#include <cstddef>
#include <string>
#include <string_view>

#include <fmt/format.h>

namespace mgrl::app {

/// `n` followed by `singular` if n is 1, else by `plural` (default: singular + "s"):
/// counted(1, "file") == "1 file", counted(3, "punch", "punches") == "3 punches".
inline std::string counted(std::size_t n, std::string_view singular, std::string_view plural = {}) {
  if (n == 1) return fmt::format("1 {}", singular);
  if (plural.empty()) return fmt::format("{} {}s", n, singular);
  return fmt::format("{} {}", n, plural);
}

}  // namespace mgrl::app
