#pragma once
/// \file
/// The project's error types. Every bad input throws a type derived from `mgrl::Error`;
/// the command line catches it once, prints its one-line message and exits non-zero.

#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace mgrl {

/// Base of every error mgrl reports about its inputs (files, options, configuration).
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

/// A malformed input file. `what()` reads `source:line: expected X, found Y`, so an editor
/// can jump to the spot. `line` is 1-based; 0 means the message concerns the whole file.
class ParseError : public Error {
 public:
  ParseError(std::string_view source, std::size_t line, std::string_view expected, std::string_view found);

  const std::string& source() const { return source_; }
  std::size_t line() const { return line_; }

 private:
  std::string source_;
  std::size_t line_;
};

/// A plug-in's check failed at one of its keys ("point", "effector"), found when it is
/// bound to a model, after its block was read: the caller, which holds the block, reports it
/// at the key (or at the block if the key was left out).
struct KeyError : Error {
  KeyError(std::string key_, const std::string& message) : Error(message), key(std::move(key_)) {}
  std::string key;
};

/// Receives non-fatal problems found in an input (one message each, no trailing newline).
/// An empty sink drops them.
using WarningSink = std::function<void(const std::string&)>;

/// Shortens a token for quoting in an error message (long garbage stays readable).
std::string quoteToken(std::string_view token);

}  // namespace mgrl
