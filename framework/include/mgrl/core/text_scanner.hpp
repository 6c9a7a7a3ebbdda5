#pragma once
/// \file
/// A whitespace tokenizer over a whole file held in memory, tracking 1-based line numbers
/// for error messages. Used by the BVH and ASF/AMC readers; not part of the public API
/// users build on, but small enough to test directly.

#include <cstddef>
#include <string>
#include <string_view>

namespace mgrl {

/// Reads whitespace-separated tokens and whole lines from `text`. Handles LF, CRLF and
/// lone CR line endings. The scanner does not own the text.
class TextScanner {
 public:
  TextScanner(std::string_view text, std::string_view source) : text_(text), source_(source) {}

  /// Next token across line breaks, or an empty view at end of input.
  std::string_view next();
  /// Next token, which must equal `keyword`; throws ParseError otherwise.
  void expect(std::string_view keyword);
  /// Next token; throws ParseError naming `what` at end of input.
  std::string_view require(std::string_view what);
  /// Next token parsed as a finite double; throws ParseError naming `what` otherwise.
  double number(std::string_view what);
  /// Next token parsed as a non-negative integer below `limit`.
  long long integer(std::string_view what, long long limit);

  /// Skips blank characters on the current line (not the line break).
  void skipBlanks();
  /// True when only whitespace is left.
  bool atEnd();
  /// Returns the rest of the current line (without its line break) and moves to the
  /// start of the next line. `line()` then reports the line just returned.
  std::string_view nextLine();

  /// Line of the last token or line returned (1-based).
  std::size_t line() const { return tokenLine_; }
  std::string_view source() const { return source_; }
  std::size_t offset() const { return pos_; }

  /// Throws ParseError at the current line.
  [[noreturn]] void fail(std::string_view expected, std::string_view found) const;
  /// Describes a token for "found ..." (end of file when empty).
  static std::string describe(std::string_view token);

 private:
  void skipSpace();

  std::string_view text_;
  std::string source_;
  std::size_t pos_ = 0;
  std::size_t line_ = 1;
  std::size_t tokenLine_ = 1;
};

/// Parses a whole token as a double. Returns false on anything else, including a partial
/// parse such as "1.5x". NaN and infinities parse (so callers can report them precisely).
bool parseDouble(std::string_view token, double& value);

/// Parses `token` as a finite double or throws ParseError at `line` of `source`.
double parseFinite(std::string_view token, std::string_view what, std::string_view source, std::size_t line);

/// Reads a whole stream into a string (binary-safe).
std::string readAll(std::istream& in);

}  // namespace mgrl
