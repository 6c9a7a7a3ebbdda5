#pragma once
/// \file
/// The words of a fixed enum, in one table per enum: parseWord() turns a word into its
/// value (or throws mgrl::Error listing the words), wordOf() a value into its word.
#include <array>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

template <class E>
struct EnumWord {
  E value;
  std::string_view word;
};

/// The value whose word is `text`; else mgrl::Error "expected one of a, b, found 'text'"
/// (no prefix: callers say where the text came from).
template <class E, std::size_t N>
E parseWord(const std::array<EnumWord<E>, N>& words, std::string_view text) {
  std::string list;
  for (const EnumWord<E>& w : words) {
    if (w.word == text) return w.value;
    list += fmt::format("{}, ", w.word);
  }
  throw Error(fmt::format("expected one of {}found '{}'", list, text));
}

/// The word of `value`; "?" for a value the table does not hold.
template <class E, std::size_t N>
std::string_view wordOf(const std::array<EnumWord<E>, N>& words, E value) {
  for (const EnumWord<E>& w : words)
    if (w.value == value) return w.word;
  return "?";
}

}  // namespace mgrl
