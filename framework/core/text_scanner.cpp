#include "mgrl/core/text_scanner.hpp"

#include <charconv>
#include <cmath>
#include <istream>
#include <iterator>
#include <sstream>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {
namespace {

bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }

// At end of input (`line` counts every line break in `text`), the line of the last
// non-whitespace character: where an editor should jump for "found end of file", rather
// than the line after a final line break, which editors do not show.
std::size_t lastContentLine(std::string_view text, std::size_t line) {
  std::size_t i = text.size();
  while (i > 0) {
    const char c = text[i - 1];
    if (c == '\n') {
      --line;
      --i;
      if (i > 0 && text[i - 1] == '\r') --i;
    } else if (c == '\r') {
      --line;
      --i;
    } else if (isBlank(c)) {
      --i;
    } else {
      break;
    }
  }
  return line > 0 ? line : 1;
}

}  // namespace

void TextScanner::skipBlanks() {
  while (pos_ < text_.size() && isBlank(text_[pos_])) ++pos_;
}

void TextScanner::skipSpace() {
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (c == '\r') {
      // CRLF counts once; a lone CR (old Mac files) counts as a line break too.
      ++line_;
      ++pos_;
      if (pos_ < text_.size() && text_[pos_] == '\n') ++pos_;
    } else if (isBlank(c)) {
      ++pos_;
    } else {
      break;
    }
  }
}

std::string_view TextScanner::next() {
  skipSpace();
  tokenLine_ = pos_ < text_.size() ? line_ : lastContentLine(text_, line_);
  const std::size_t start = pos_;
  while (pos_ < text_.size()) {
    const char c = text_[pos_];
    if (isBlank(c) || c == '\n' || c == '\r') break;
    ++pos_;
  }
  return text_.substr(start, pos_ - start);
}

bool TextScanner::atEnd() {
  skipSpace();
  tokenLine_ = pos_ < text_.size() ? line_ : lastContentLine(text_, line_);
  return pos_ >= text_.size();
}

std::string_view TextScanner::nextLine() {
  tokenLine_ = line_;
  const std::size_t start = pos_;
  while (pos_ < text_.size() && text_[pos_] != '\n' && text_[pos_] != '\r') ++pos_;
  const std::string_view result = text_.substr(start, pos_ - start);
  if (pos_ < text_.size()) {
    if (text_[pos_] == '\r' && pos_ + 1 < text_.size() && text_[pos_ + 1] == '\n') ++pos_;
    ++pos_;
    ++line_;
  }
  return result;
}

void TextScanner::expect(std::string_view keyword) {
  const std::string_view token = next();
  if (token != keyword) fail(fmt::format("'{}'", keyword), describe(token));
}

std::string_view TextScanner::require(std::string_view what) {
  const std::string_view token = next();
  if (token.empty()) fail(what, "end of file");
  return token;
}

double TextScanner::number(std::string_view what) {
  const std::string_view token = next();
  if (token.empty()) fail(what, "end of file");
  return parseFinite(token, what, source_, tokenLine_);
}

long long TextScanner::integer(std::string_view what, long long limit) {
  const std::string_view token = next();
  if (token.empty()) fail(what, "end of file");
  long long value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec == std::errc::result_out_of_range || (ec == std::errc() && end == token.data() + token.size() &&
                                               (value < 0 || value > limit)))
    fail(fmt::format("{} between 0 and {}", what, limit), describe(token));
  if (ec != std::errc() || end != token.data() + token.size()) fail(what, describe(token));
  return value;
}

void TextScanner::fail(std::string_view expected, std::string_view found) const {
  throw ParseError(source_, tokenLine_, expected, found);
}

std::string TextScanner::describe(std::string_view token) {
  return token.empty() ? std::string("end of file") : quoteToken(token);
}

bool parseDouble(std::string_view token, double& value) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  // from_chars rejects a leading '+', which some exporters write.
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  const auto [end, ec] = std::from_chars(first, last, value);
  if (ec == std::errc::result_out_of_range) {
    value = HUGE_VAL;  // reported as not finite by the caller
    return end == last;
  }
  return ec == std::errc() && end == last;
}

double parseFinite(std::string_view token, std::string_view what, std::string_view source,
                   std::size_t line) {
  double value = 0;
  if (!parseDouble(token, value)) throw ParseError(source, line, what, TextScanner::describe(token));
  if (!std::isfinite(value))
    throw ParseError(source, line, "a finite number", TextScanner::describe(token));
  return value;
}

std::string readAll(std::istream& in) {
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return std::move(buffer).str();
}

}  // namespace mgrl
