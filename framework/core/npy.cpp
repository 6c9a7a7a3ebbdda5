#include "mgrl/core/npy.hpp"

#include <bit>
#include <cstring>
#include <limits>
#include <optional>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"

namespace mgrl {
namespace {

constexpr std::string_view kMagic = "\x93NUMPY";
constexpr std::size_t kAlignment = 64;  // NumPy aligns the data so it can be memory-mapped

static_assert(std::numeric_limits<float>::is_iec559 && std::numeric_limits<double>::is_iec559,
              ".npy stores IEEE-754 floats");

// Python's repr of a tuple: (), (3,), (2, 3).
std::string shapeText(const std::vector<std::size_t>& shape) {
  if (shape.size() == 1) return fmt::format("({},)", shape[0]);
  return fmt::format("({})", fmt::join(shape, ", "));
}

// Product of the dimensions, or nothing if it overflows size_t.
std::optional<std::size_t> elementCount(const std::vector<std::size_t>& shape) {
  for (std::size_t d : shape)
    if (d == 0) return 0;
  std::size_t count = 1;
  for (std::size_t d : shape) {
    if (count > std::numeric_limits<std::size_t>::max() / d) return std::nullopt;
    count *= d;
  }
  return count;
}

// The element's bytes as an unsigned integer of the same size, for byte-order conversion.
template <class T>
using Bits = std::conditional_t<sizeof(T) == 1, std::uint8_t,
                                std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>;

template <class T>
void appendLittleEndian(std::string& out, std::span<const T> data) {
  if constexpr (std::endian::native == std::endian::little) {
    out.append(reinterpret_cast<const char*>(data.data()), data.size_bytes());
  } else {
    for (T value : data) {
      const auto bits = std::bit_cast<Bits<T>>(value);
      for (std::size_t i = 0; i < sizeof(T); ++i) out.push_back(static_cast<char>((bits >> (8 * i)) & 0xff));
    }
  }
}

template <class T>
void readLittleEndian(std::string_view bytes, std::vector<T>& out) {
  if constexpr (std::endian::native == std::endian::little) {
    if (!out.empty()) std::memcpy(out.data(), bytes.data(), bytes.size());
  } else {
    for (std::size_t k = 0; k < out.size(); ++k) {
      Bits<T> bits = 0;
      for (std::size_t i = sizeof(T); i-- > 0;)
        bits = static_cast<Bits<T>>((bits << 8) | static_cast<unsigned char>(bytes[k * sizeof(T) + i]));
      out[k] = std::bit_cast<T>(bits);
    }
  }
}

struct Header {
  std::optional<std::string> descr;
  std::optional<bool> fortranOrder;
  std::optional<std::vector<std::size_t>> shape;
};

// A recursive-descent reader for the one Python literal a .npy header holds:
// {'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }
class HeaderParser {
 public:
  HeaderParser(std::string_view text, std::string_view source) : text_(text), source_(source) {}

  Header parse() {
    Header header;
    skipSpace();
    expect('{', "'{' opening the header dict");
    skipSpace();
    while (!consume('}')) {
      const std::size_t keyAt = pos_;
      const std::string key = string("a quoted key or '}' in the header dict");
      skipSpace();
      expect(':', fmt::format("':' after key '{}'", key));
      skipSpace();
      if (key == "descr") {
        if (header.descr) duplicate(key);
        header.descr = string("a quoted type string for 'descr'");
      } else if (key == "fortran_order") {
        if (header.fortranOrder) duplicate(key);
        header.fortranOrder = boolean();
      } else if (key == "shape") {
        if (header.shape) duplicate(key);
        header.shape = tuple();
      } else {
        pos_ = keyAt;
        fail("one of the keys 'descr', 'fortran_order', 'shape'");
      }
      skipSpace();
      if (consume(',')) {
        skipSpace();
      } else if (pos_ >= text_.size() || text_[pos_] != '}') {
        fail("',' or '}' in the header dict");
      }
    }
    skipSpace();
    if (pos_ != text_.size()) fail("the end of the header after '}'");
    return header;
  }

 private:
  void skipSpace() {
    while (pos_ < text_.size() && (text_[pos_] == ' ' || text_[pos_] == '\t' || text_[pos_] == '\n' ||
                                   text_[pos_] == '\r'))
      ++pos_;
  }

  bool consume(char c) {
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  void expect(char c, std::string_view what) {
    if (!consume(c)) fail(what);
  }

  [[noreturn]] void fail(std::string_view expected) const {
    const std::string found =
        pos_ >= text_.size() ? std::string("the end of the header") : quoteToken(text_.substr(pos_));
    throw ParseError(source_, 0, expected, found);
  }

  [[noreturn]] void duplicate(const std::string& key) const {
    throw ParseError(source_, 0, "each header key once", fmt::format("'{}' twice", key));
  }

  // A Python string literal without escapes: '...' or "...".
  std::string string(std::string_view what) {
    if (pos_ >= text_.size() || (text_[pos_] != '\'' && text_[pos_] != '"')) fail(what);
    const std::size_t start = pos_;
    const char quote = text_[pos_++];
    const std::size_t end = text_.find(quote, pos_);
    const std::string_view body = text_.substr(pos_, end == std::string_view::npos ? 0 : end - pos_);
    if (end == std::string_view::npos || body.find_first_of("\\\n\r") != std::string_view::npos) {
      pos_ = start;
      fail(fmt::format("{} (closed on its line, without escapes)", what));
    }
    pos_ = end + 1;
    return std::string(body);
  }

  bool boolean() {
    if (text_.substr(pos_).starts_with("True")) {
      pos_ += 4;
      return true;
    }
    if (text_.substr(pos_).starts_with("False")) {
      pos_ += 5;
      return false;
    }
    fail("True or False for 'fortran_order'");
  }

  // A tuple of non-negative decimal integers: (), (3,), (2, 3), (2, 3,).
  std::vector<std::size_t> tuple() {
    expect('(', "a tuple such as (2, 3) for 'shape'");
    std::vector<std::size_t> dims;
    skipSpace();
    bool comma = false;
    while (!consume(')')) {
      dims.push_back(integer());
      skipSpace();
      comma = consume(',');
      skipSpace();
      if (!comma && (pos_ >= text_.size() || text_[pos_] != ')')) fail("',' or ')' in 'shape'");
    }
    // (3) is the integer 3 in Python, not a tuple.
    if (dims.size() == 1 && !comma) {
      pos_ -= 1;
      fail("',' after the only dimension in 'shape', as in (3,)");
    }
    return dims;
  }

  std::size_t integer() {
    const std::size_t start = pos_;
    if (pos_ >= text_.size() || text_[pos_] < '0' || text_[pos_] > '9')
      fail("a non-negative integer dimension in 'shape'");
    std::size_t value = 0;
    while (pos_ < text_.size() && text_[pos_] >= '0' && text_[pos_] <= '9') {
      const auto digit = static_cast<std::size_t>(text_[pos_] - '0');
      if (value > (std::numeric_limits<std::size_t>::max() - digit) / 10) {
        pos_ = start;
        fail(fmt::format("a dimension below 2^{} in 'shape'", std::numeric_limits<std::size_t>::digits));
      }
      value = value * 10 + digit;
      ++pos_;
    }
    if (text_[start] == '0' && pos_ - start > 1) {
      pos_ = start;
      fail("a decimal dimension without leading zeros in 'shape'");
    }
    return value;
  }

  std::string_view text_;
  std::string_view source_;
  std::size_t pos_ = 0;
};

}  // namespace

template <NpyElement T>
std::string npyEncode(std::span<const T> data, const std::vector<std::size_t>& shape) {
  const std::optional<std::size_t> count = elementCount(shape);
  if (!count || *count != data.size())
    throw Error(fmt::format("npyEncode: expected a shape of {} elements, found {} ({} elements)", data.size(),
                            shapeText(shape), count ? fmt::format("{}", *count) : std::string("too many")));
  const std::string dict =
      fmt::format("{{'descr': '{}', 'fortran_order': False, 'shape': {}, }}", npyDescr<T>(), shapeText(shape));
  constexpr std::size_t kPrefix = 10;  // magic, version, 2-byte header length
  const std::size_t unpadded = kPrefix + dict.size() + 1;
  const std::size_t headerLength = (unpadded + kAlignment - 1) / kAlignment * kAlignment - kPrefix;
  if (headerLength > 0xffff)
    throw Error(fmt::format("npyEncode: expected a header under 65536 bytes, found {} for shape of rank {}",
                            headerLength, shape.size()));
  std::string out;
  out.reserve(kPrefix + headerLength + data.size_bytes());
  out += kMagic;
  out.push_back('\x01');
  out.push_back('\x00');
  out.push_back(static_cast<char>(headerLength & 0xff));
  out.push_back(static_cast<char>(headerLength >> 8));
  out += dict;
  out.append(headerLength - dict.size() - 1, ' ');
  out.push_back('\n');
  appendLittleEndian(out, data);
  return out;
}

namespace {

// The data bytes of a checked .npy file (every check npyDecode() promises), and its shape.
template <NpyElement T>
std::string_view npyPayload(std::string_view bytes, std::string_view source, std::vector<std::size_t>& shapeOut) {
  // A prefix of the magic is a truncated file; anything else is not a .npy file at all.
  const bool truncatedMagic = !bytes.empty() && bytes.size() < kMagic.size() && kMagic.starts_with(bytes);
  if (!bytes.starts_with(kMagic) && !truncatedMagic)
    throw ParseError(source, 0, "a .npy file starting with '\\x93NUMPY'",
                     bytes.empty() ? std::string("an empty file") : quoteToken(bytes.substr(0, kMagic.size())));
  if (bytes.size() < 10)
    throw ParseError(source, 0, "a .npy header of at least 10 bytes", fmt::format("{} bytes", bytes.size()));
  const auto major = static_cast<unsigned char>(bytes[6]);
  const auto minor = static_cast<unsigned char>(bytes[7]);
  if ((major != 1 && major != 2) || minor != 0)
    throw ParseError(source, 0, ".npy format version 1.0 or 2.0", fmt::format("version {}.{}", major, minor));
  // Format 2.0 widens the header length from 2 to 4 bytes.
  const std::size_t lengthBytes = major == 1 ? 2 : 4;
  const std::size_t prefix = 8 + lengthBytes;
  if (bytes.size() < prefix)
    throw ParseError(source, 0, fmt::format("a .npy {}.0 header of at least {} bytes", major, prefix),
                     fmt::format("{} bytes", bytes.size()));
  std::uint64_t headerLength = 0;
  for (std::size_t i = lengthBytes; i-- > 0;)
    headerLength = (headerLength << 8) | static_cast<unsigned char>(bytes[8 + i]);
  if (headerLength > bytes.size() - prefix)
    throw ParseError(source, 0,
                     fmt::format("a header length within the file's {} bytes", bytes.size()),
                     fmt::format("a header of {} bytes after the {}-byte prefix", headerLength, prefix));
  const std::string_view headerText = bytes.substr(prefix, headerLength);
  const Header header = HeaderParser(headerText, source).parse();
  if (!header.descr) throw ParseError(source, 0, "the header key 'descr'", "none");
  if (!header.fortranOrder) throw ParseError(source, 0, "the header key 'fortran_order'", "none");
  if (!header.shape) throw ParseError(source, 0, "the header key 'shape'", "none");
  if (*header.descr != npyDescr<T>())
    throw ParseError(source, 0, fmt::format("descr '{}'", npyDescr<T>()), quoteToken(*header.descr));
  if (*header.fortranOrder) throw ParseError(source, 0, "fortran_order False (C order)", "True");

  const std::optional<std::size_t> count = elementCount(*header.shape);
  if (!count || *count > std::numeric_limits<std::size_t>::max() / sizeof(T))
    throw ParseError(source, 0,
                     fmt::format("a shape whose data fits in 2^{} bytes", std::numeric_limits<std::size_t>::digits),
                     shapeText(*header.shape));
  const std::string_view payload = bytes.substr(prefix + headerLength);
  if (*count * sizeof(T) != payload.size())
    throw ParseError(source, 0,
                     fmt::format("{} data bytes for shape {} of '{}'", *count * sizeof(T), shapeText(*header.shape),
                                 npyDescr<T>()),
                     fmt::format("{} bytes", payload.size()));
  shapeOut = *header.shape;
  return payload;
}

}  // namespace

template <NpyElement T>
std::vector<T> npyDecode(std::string_view bytes, std::string_view source, std::vector<std::size_t>* shape) {
  std::vector<std::size_t> dims;
  const std::string_view payload = npyPayload<T>(bytes, source, dims);
  std::vector<T> data(payload.size() / sizeof(T));
  readLittleEndian(payload, data);
  if (shape) *shape = std::move(dims);
  return data;
}

template <NpyElement T>
std::optional<std::span<const T>> npyView(std::string_view bytes, std::string_view source,
                                          std::vector<std::size_t>* shape) {
  std::vector<std::size_t> dims;
  const std::string_view payload = npyPayload<T>(bytes, source, dims);
  if (shape) *shape = std::move(dims);
  if constexpr (std::endian::native != std::endian::little) return std::nullopt;
  if (reinterpret_cast<std::uintptr_t>(payload.data()) % alignof(T) != 0) return std::nullopt;
  return std::span<const T>(reinterpret_cast<const T*>(payload.data()), payload.size() / sizeof(T));
}

#define MGRL_NPY_INSTANTIATE(T)                                                             \
  template std::string npyEncode<T>(std::span<const T>, const std::vector<std::size_t>&); \
  template std::vector<T> npyDecode<T>(std::string_view, std::string_view, std::vector<std::size_t>*); \
  template std::optional<std::span<const T>> npyView<T>(std::string_view, std::string_view, std::vector<std::size_t>*);
MGRL_NPY_INSTANTIATE(std::uint8_t)
MGRL_NPY_INSTANTIATE(std::uint32_t)
MGRL_NPY_INSTANTIATE(std::int32_t)
MGRL_NPY_INSTANTIATE(float)
MGRL_NPY_INSTANTIATE(double)
#undef MGRL_NPY_INSTANTIATE

}  // namespace mgrl
