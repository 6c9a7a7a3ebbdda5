#pragma once
/// \file
/// NumPy .npy files (https://numpy.org/doc/stable/reference/generated/numpy.lib.format.html),
/// so the arrays mgrl caches open in NumPy with `numpy.load`. The writer emits format 1.0
/// in C order, little-endian; the reader accepts formats 1.0 and 2.0 and checks everything
/// a hostile or damaged file could get wrong before allocating.

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mgrl {

/// The element types mgrl stores in .npy files; npy.cpp instantiates the functions below
/// for each.
template <class T>
concept NpyElement = std::same_as<T, std::uint8_t> || std::same_as<T, std::uint32_t> || std::same_as<T, std::int32_t> ||
    std::same_as<T, float> || std::same_as<T, double>;

/// NumPy's type string for T: "|u1", "<u4", "<i4", "<f4" or "<f8".
template <NpyElement T>
constexpr std::string_view npyDescr() {
  if constexpr (std::same_as<T, std::uint8_t>)
    return "|u1";
  else if constexpr (std::same_as<T, std::uint32_t>)
    return "<u4";
  else if constexpr (std::same_as<T, std::int32_t>)
    return "<i4";
  else if constexpr (std::same_as<T, float>)
    return "<f4";
  else
    return "<f8";
}

/// A whole .npy file (format 1.0) holding `data` in C order with dimensions `shape` (an
/// empty shape is a 0-d array of one element). The header is padded with spaces and ends
/// in '\n' so that the data starts at a multiple of 64 bytes, as NumPy writes it. Call as
/// `npyEncode<float>(vector, {rows, 3})`.
/// Throws mgrl::Error if the product of `shape` differs from `data.size()`, or if the
/// shape is too long for a 1.0 header (65535 bytes).
template <NpyElement T>
std::string npyEncode(std::span<const T> data, const std::vector<std::size_t>& shape);

/// The array in a whole .npy file `bytes` (format 1.0 or 2.0), in C order. `source` names
/// the file in error messages. If `shape` is given it receives the dimensions.
/// Strict: the header must be a Python dict literal with exactly the keys 'descr',
/// 'fortran_order' and 'shape' (any order, either quote, trailing comma allowed), descr must
/// be exactly npyDescr<T>() (no conversions), fortran_order False, and the shape's element
/// count times sizeof(T) must equal the bytes after the header.
/// Throws mgrl::ParseError(source, 0, expected, found) for any problem; allocates only
/// after the size check, so at most the size of `bytes`.
template <NpyElement T>
std::vector<T> npyDecode(std::string_view bytes, std::string_view source, std::vector<std::size_t>* shape = nullptr);

/// The same checks as npyDecode(), but the array is read in place: a view into `bytes`
/// (which must outlive it), or nullopt where it cannot be (a big-endian host, or data not
/// aligned for T: then use npyDecode()).
template <NpyElement T>
std::optional<std::span<const T>> npyView(std::string_view bytes, std::string_view source,
                                          std::vector<std::size_t>* shape = nullptr);

}  // namespace mgrl
