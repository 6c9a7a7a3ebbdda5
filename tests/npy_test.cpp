// NumPy .npy files: the writer's exact bytes (header text, 64-byte alignment), round trips
// of every element type, and one test per way the strict reader refuses a bad file.

#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/core/npy.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace npy_test {

using Catch::Contains;
using mgrl::npyDecode;
using mgrl::npyEncode;
using mgrl::ParseError;


namespace {

// A .npy file with a hand-written header (no padding added), for malformed input.
std::string npyWithHeader(std::string_view header, std::string_view payload, unsigned char major = 1) {
  std::string out("\x93NUMPY", 6);
  out.push_back(static_cast<char>(major));
  out.push_back('\0');
  const std::size_t lengthBytes = major == 1 ? 2 : 4;
  for (std::size_t i = 0; i < lengthBytes; ++i) out.push_back(static_cast<char>((header.size() >> (8 * i)) & 0xff));
  out += header;
  out += payload;
  return out;
}

// Three little-endian doubles 1, 2, 3.
std::string threeDoubles() {
  std::string payload;
  for (double v : {1.0, 2.0, 3.0}) {
    char bytes[8];
    std::memcpy(bytes, &v, 8);
    payload.append(bytes, 8);
  }
  return payload;
}

std::size_t dataOffset(const std::string& file) {
  return 10 + static_cast<unsigned char>(file[8]) + 256 * static_cast<unsigned char>(file[9]);
}

template <class T>
std::vector<T> samples() {
  using L = std::numeric_limits<T>;
  if constexpr (std::is_floating_point_v<T>)
    return {T(0), T(-0.0), T(1.5), T(-2.25), L::min(), L::denorm_min(), L::max(), L::lowest(), L::infinity(),
            -L::infinity(), L::quiet_NaN(), T(0.1)};
  else
    return {T(0), T(1), T(7), L::min(), L::max(), T(L::max() - 1)};
}

}  // namespace

TEST_CASE("npyEncode writes NumPy's header for a small array", "[npy]") {
  const std::vector<double> data = {1.0, 2.0, 3.0};
  const std::string file = npyEncode<double>(data, {3});
  const std::string dict = "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }";
  std::string expected("\x93NUMPY\x01\x00", 8);
  expected += "\x76";  // header length 118, little-endian
  expected.push_back('\0');
  expected += dict + std::string(60, ' ') + "\n";
  expected += threeDoubles();
  REQUIRE(file == expected);
  REQUIRE(dataOffset(file) == 128);
}

TEST_CASE("npyEncode aligns the data to 64 bytes and writes Python tuples", "[npy]") {
  const std::vector<float> six(6, 1.0f);
  const std::string matrix = npyEncode<float>(six, {2, 3});
  REQUIRE(dataOffset(matrix) % 64 == 0);
  REQUIRE(matrix[dataOffset(matrix) - 1] == '\n');
  REQUIRE_THAT(matrix, Contains("'descr': '<f4', 'fortran_order': False, 'shape': (2, 3), }"));
  REQUIRE(matrix.size() == dataOffset(matrix) + 6 * sizeof(float));

  const std::vector<std::uint8_t> one = {9};
  const std::string scalar = npyEncode<std::uint8_t>(one, {});
  REQUIRE_THAT(scalar, Contains("'descr': '|u1', 'fortran_order': False, 'shape': (), }"));
  REQUIRE(dataOffset(scalar) % 64 == 0);

  // A shape whose header crosses a 64-byte boundary still aligns.
  const std::vector<std::int32_t> none;
  const std::string wide = npyEncode<std::int32_t>(none, {0, 1000000000, 1000000000, 1000000000, 7});
  REQUIRE(dataOffset(wide) % 64 == 0);
  REQUIRE(dataOffset(wide) > 64);
}

TEST_CASE("npyEncode refuses a shape that does not match the data", "[npy]") {
  const std::vector<std::uint32_t> data(6);
  REQUIRE_THROWS_AS(npyEncode<std::uint32_t>(data, {4}), mgrl::Error);
  REQUIRE_THROWS_WITH(npyEncode<std::uint32_t>(data, {4}), Contains("expected a shape of 6 elements, found (4,)"));
  REQUIRE_THROWS_WITH(npyEncode<std::uint32_t>(data, {1ull << 40, 1ull << 40}), Contains("too many"));
}

TEMPLATE_TEST_CASE("npy round-trips every element type bit for bit", "[npy]", std::uint8_t, std::uint32_t,
                   std::int32_t, float, double) {
  const std::vector<TestType> data = samples<TestType>();
  REQUIRE(data.size() % 2 == 0);
  const std::vector<std::size_t> shape = {2, data.size() / 2};
  const std::string file = npyEncode<TestType>(data, shape);
  REQUIRE(dataOffset(file) % 64 == 0);
  REQUIRE_THAT(file, Contains(fmt::format("'descr': '{}'", mgrl::npyDescr<TestType>())));

  std::vector<std::size_t> decodedShape;
  const std::vector<TestType> decoded = npyDecode<TestType>(file, "x.npy", &decodedShape);
  REQUIRE(decodedShape == shape);
  REQUIRE(decoded.size() == data.size());
  // Bitwise, so NaN and -0.0 count too.
  REQUIRE(std::memcmp(decoded.data(), data.data(), data.size() * sizeof(TestType)) == 0);
}

TEMPLATE_TEST_CASE("npy round-trips empty arrays", "[npy]", std::uint8_t, std::uint32_t, std::int32_t, float,
                   double) {
  const std::vector<TestType> empty;
  for (const std::vector<std::size_t>& shape : {std::vector<std::size_t>{0}, std::vector<std::size_t>{0, 3},
                                                 std::vector<std::size_t>{4, 0}}) {
    const std::string file = npyEncode<TestType>(empty, shape);
    REQUIRE(file.size() == dataOffset(file));
    std::vector<std::size_t> decodedShape;
    REQUIRE(npyDecode<TestType>(file, "empty.npy", &decodedShape).empty());
    REQUIRE(decodedShape == shape);
  }
}

TEST_CASE("npyDecode accepts any key order, either quote and no trailing comma", "[npy]") {
  const std::string file =
      npyWithHeader("  {\"shape\": ( 3 , ) ,'fortran_order':False,\n 'descr' : \"<f8\"}  \n", threeDoubles());
  std::vector<std::size_t> shape;
  REQUIRE(npyDecode<double>(file, "x.npy", &shape) == std::vector<double>{1, 2, 3});
  REQUIRE(shape == std::vector<std::size_t>{3});
  const std::string matrix =
      npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (1, 3,)}", threeDoubles());
  REQUIRE(npyDecode<double>(matrix, "x.npy", &shape).size() == 3);
  REQUIRE(shape == std::vector<std::size_t>{1, 3});
}

TEST_CASE("npyDecode reads format 2.0 headers", "[npy]") {
  const std::string file =
      npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }\n", threeDoubles(), 2);
  REQUIRE(npyDecode<double>(file, "x.npy") == std::vector<double>{1, 2, 3});
}

TEST_CASE("npyDecode refuses a file without the NumPy magic", "[npy]") {
  std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  file[1] = 'X';
  REQUIRE_PARSE_ERROR(npyDecode<double>(file, "bad.npy"),
                      "bad.npy: expected a .npy file starting with '\\x93NUMPY', found '\\x93XUMPY'");
  REQUIRE_PARSE_ERROR(npyDecode<double>("", "empty.npy"), "found an empty file");
  REQUIRE_PARSE_ERROR(npyDecode<double>("{'descr': '<f8'}", "text.npy"), "found '{'desc'");
}

TEST_CASE("npyDecode refuses a file cut before the header length", "[npy]") {
  const std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  REQUIRE_PARSE_ERROR(npyDecode<double>(file.substr(0, 8), "cut.npy"),
                      "cut.npy: expected a .npy header of at least 10 bytes, found 8 bytes");
  REQUIRE_PARSE_ERROR(npyDecode<double>(file.substr(0, 3), "cut.npy"), "found 3 bytes");
  const std::string v2 = npyWithHeader("{}", "", 2);
  REQUIRE_PARSE_ERROR(npyDecode<double>(v2.substr(0, 11), "cut.npy"),
                      "expected a .npy 2.0 header of at least 12 bytes, found 11 bytes");
}

TEST_CASE("npyDecode refuses a header length past the end of the file", "[npy]") {
  const std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  REQUIRE_PARSE_ERROR(npyDecode<double>(file.substr(0, 50), "cut.npy"),
                      "cut.npy: expected a header length within the file's 50 bytes, found a header of 118 bytes");
  // The widest 2.0 length cannot wrap around the check.
  std::string huge = npyWithHeader("", "", 2);
  huge.replace(8, 4, "\xff\xff\xff\xff");
  REQUIRE_PARSE_ERROR(npyDecode<double>(huge, "huge.npy"), "found a header of 4294967295 bytes");
}

TEST_CASE("npyDecode refuses unknown format versions", "[npy]") {
  std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  file[6] = '\x03';
  REQUIRE_PARSE_ERROR(npyDecode<double>(file, "v3.npy"), "expected .npy format version 1.0 or 2.0, found version 3.0");
}

TEST_CASE("npyDecode refuses a descr other than the element type's", "[npy]") {
  const std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  REQUIRE_PARSE_ERROR(npyDecode<float>(file, "f8.npy"), "f8.npy: expected descr '<f4', found '<f8'");
  REQUIRE_PARSE_ERROR(npyDecode<std::int32_t>(npyEncode<std::uint32_t>(std::vector<std::uint32_t>{1}, {1}), "u4.npy"),
                      "expected descr '<i4', found '<u4'");
  const std::string bigEndian =
      npyWithHeader("{'descr': '>f8', 'fortran_order': False, 'shape': (3,), }", threeDoubles());
  REQUIRE_PARSE_ERROR(npyDecode<double>(bigEndian, "be.npy"), "expected descr '<f8', found '>f8'");
}

TEST_CASE("npyDecode refuses Fortran-order arrays", "[npy]") {
  const std::string file = npyWithHeader("{'descr': '<f8', 'fortran_order': True, 'shape': (3,), }", threeDoubles());
  REQUIRE_PARSE_ERROR(npyDecode<double>(file, "f.npy"), "f.npy: expected fortran_order False (C order), found True");
}

TEST_CASE("npyDecode refuses negative dimensions", "[npy]") {
  const std::string file = npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (-3,), }", threeDoubles());
  REQUIRE_PARSE_ERROR(npyDecode<double>(file, "neg.npy"),
                      "expected a non-negative integer dimension in 'shape', found '-3,), }'");
}

TEST_CASE("npyDecode refuses huge shapes without allocating", "[npy]") {
  const std::string big =
      npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000000000,), }", threeDoubles());
  REQUIRE_PARSE_ERROR(npyDecode<double>(big, "big.npy"),
                      "expected 8000000000000000000 data bytes for shape (1000000000000000000,) of '<f8', found 24 bytes");
  const std::string overflow = npyWithHeader(
      "{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000000000, 1000000000000000000), }", "");
  REQUIRE_PARSE_ERROR(npyDecode<double>(overflow, "overflow.npy"), "expected a shape whose data fits in 2^64 bytes");
  // The element count fits, the byte count does not.
  const std::string bytesOverflow =
      npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (4611686018427387904,), }", "");
  REQUIRE_PARSE_ERROR(npyDecode<double>(bytesOverflow, "overflow.npy"), "expected a shape whose data fits");
  const std::string digits =
      npyWithHeader("{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999999,), }", "");
  REQUIRE_PARSE_ERROR(npyDecode<double>(digits, "digits.npy"), "expected a dimension below 2^64 in 'shape'");
}

TEST_CASE("npyDecode refuses a payload shorter or longer than the shape", "[npy]") {
  const std::string file = npyEncode<double>(std::vector<double>{1, 2, 3}, {3});
  REQUIRE_PARSE_ERROR(npyDecode<double>(file.substr(0, file.size() - 1), "short.npy"),
                      "short.npy: expected 24 data bytes for shape (3,) of '<f8', found 23 bytes");
  REQUIRE_PARSE_ERROR(npyDecode<double>(file + "x", "long.npy"),
                      "expected 24 data bytes for shape (3,) of '<f8', found 25 bytes");
}

TEST_CASE("npyDecode refuses a header that is not the expected dict", "[npy]") {
  auto decode = [](std::string_view header, std::string_view payload = "") {
    return npyDecode<double>(npyWithHeader(header, payload), "h.npy");
  };
  REQUIRE_PARSE_ERROR(decode("hello"), "h.npy: expected '{' opening the header dict, found 'hello'");
  REQUIRE_PARSE_ERROR(decode(""), "expected '{' opening the header dict, found the end of the header");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8', 'fortran_order': False"),
                      "expected ',' or '}' in the header dict, found the end");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8' 'fortran_order': False}"),
                      "expected ',' or '}' in the header dict, found ''fortran_order'");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8', 'fortran_order': False, 'shape': (3,)} x", threeDoubles()),
                      "expected the end of the header after '}', found 'x'");
  REQUIRE_PARSE_ERROR(decode("{descr: '<f8'}"), "expected a quoted key or '}' in the header dict, found 'descr");
  REQUIRE_PARSE_ERROR(decode("{'descr' '<f8'}"), "expected ':' after key 'descr'");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8}"), "expected a quoted type string for 'descr' (closed on its line");
  REQUIRE_PARSE_ERROR(decode("{'descr': 8}"), "expected a quoted type string for 'descr'");
  REQUIRE_PARSE_ERROR(decode("{'fortran_order': 0}"), "expected True or False for 'fortran_order', found '0}'");
  REQUIRE_PARSE_ERROR(decode("{'shape': [3]}"), "expected a tuple such as (2, 3) for 'shape', found '[3]}'");
  REQUIRE_PARSE_ERROR(decode("{'shape': (3)}"), "expected ',' after the only dimension in 'shape', as in (3,)");
  REQUIRE_PARSE_ERROR(decode("{'shape': (3 4)}"), "expected ',' or ')' in 'shape', found '4)}'");
  REQUIRE_PARSE_ERROR(decode("{'shape': (03,)}"), "expected a decimal dimension without leading zeros");
  REQUIRE_PARSE_ERROR(decode("{'shape': (3.0,)}"), "expected ',' or ')' in 'shape', found '.0,)}'");
  REQUIRE_PARSE_ERROR(decode("{'dtype': '<f8'}"),
                      "expected one of the keys 'descr', 'fortran_order', 'shape', found ''dtype'");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8', 'descr': '<f8'}"), "expected each header key once, found 'descr' twice");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8', 'fortran_order': False}"),
                      "expected the header key 'shape', found none");
  REQUIRE_PARSE_ERROR(decode("{'shape': (3,), 'fortran_order': False}"), "expected the header key 'descr', found none");
  REQUIRE_PARSE_ERROR(decode("{'descr': '<f8', 'shape': (3,)}"), "expected the header key 'fortran_order', found none");
  // Control bytes from a damaged file are shown escaped.
  REQUIRE_PARSE_ERROR(decode(std::string_view("{\x01\x02}", 4)), "found '\\x01\\x02}'");
}

}  // namespace npy_test
