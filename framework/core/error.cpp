#include "mgrl/core/error.hpp"

#include <fmt/format.h>

namespace mgrl {
namespace {

std::string formatParseError(std::string_view source, std::size_t line,
                             std::string_view expected, std::string_view found) {
  if (line == 0) return fmt::format("{}: expected {}, found {}", source, expected, found);
  return fmt::format("{}:{}: expected {}, found {}", source, line, expected, found);
}

}  // namespace

ParseError::ParseError(std::string_view source, std::size_t line, std::string_view expected,
                       std::string_view found)
    : Error(formatParseError(source, line, expected, found)), source_(source), line_(line) {}

std::string quoteToken(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string shown;
  for (char c : token.substr(0, kMax)) {
    // Control bytes from a corrupt file would garble the terminal; show them escaped.
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f)
      shown += fmt::format("\\x{:02x}", static_cast<unsigned char>(c));
    else
      shown += c;
  }
  if (token.size() > kMax) shown.append(3, '.');
  return "'" + shown + "'";
}

}  // namespace mgrl
