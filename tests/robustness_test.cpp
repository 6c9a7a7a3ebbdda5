// Corrupt input never crashes the loaders and never escapes as anything but mgrl::Error:
// every truncation of a small valid file, and a few thousand seeded single-byte mutations.

#include <array>
#include <cstdint>
#include <random>
#include <string>
#include <typeinfo>

#include <catch2/catch.hpp>

#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace robustness_test {

namespace {

constexpr std::uint64_t kRootSeed = 20040827;  // any fixed value; printed on failure
constexpr int kMutations = 3000;

// Bytes that steer a text parser somewhere new more often than a uniformly random byte.
constexpr std::array<char, 22> kStructural = {'{', '}', '\n', '\r', ' ', '\t', '-', '+', '.', 'e', '0', '9',
                                              ':', '#', '(', ')', '\0', 'n', 'i', 'x', 'r', '\xff'};

// Empty when `parse` succeeds or throws mgrl::Error; otherwise what escaped.
template <class Parse>
std::string escaped(Parse&& parse) {
  try {
    parse();
    return {};
  } catch (const mgrl::Error&) {
    return {};
  } catch (const std::exception& e) {
    return std::string(typeid(e).name()) + ": " + e.what();
  } catch (...) {
    return "an exception not derived from std::exception";
  }
}

// Tallies inputs whose parse let something other than mgrl::Error escape, keeping the first
// for the failure message.
struct Failures {
  int count = 0;
  std::string first;

  void record(const std::string& what, const std::string& input) {
    if (what.empty()) return;
    if (count++ == 0) first = input + " -> " + what;
  }
};

// One seeded single-byte change: replace, insert or delete a byte. Returns a description.
std::string mutate(std::string& text, std::mt19937_64& rng) {
  const int kind = static_cast<int>(rng() % 4);  // 0, 1: replace; 2: insert; 3: delete
  const std::size_t pos = static_cast<std::size_t>(rng() % (text.size() + (kind == 2 ? 1 : 0)));
  const char byte = rng() % 2 ? kStructural[rng() % kStructural.size()] : static_cast<char>(rng() % 256);
  const std::string shown = std::to_string(static_cast<int>(static_cast<unsigned char>(byte)));
  if (kind == 2) {
    text.insert(pos, 1, byte);
    return "insert byte " + shown + " at " + std::to_string(pos);
  }
  if (kind == 3) {
    text.erase(pos, 1);
    return "delete byte at " + std::to_string(pos);
  }
  text[pos] = byte;
  return "byte " + std::to_string(pos) + " := " + shown;
}

void parseAsfAndAmc(const std::string& asfText, const std::string& amcText) {
  const mgrl::AsfSkeleton skeleton = mgrl::parseAsf(asfText, "tiny.asf");
  mgrl::parseAmc(amcText, "tiny_01.amc", skeleton);
}

}  // namespace

TEST_CASE("bvh loader survives every truncation and seeded byte mutations", "[loader][robustness]") {
  const std::string original = mgrl::readFile(mgrl::test::testData() / "tiny.bvh");
  const mgrl::WarningSink quiet = [](const std::string&) {};
  REQUIRE_NOTHROW(mgrl::parseBvh(original, "tiny.bvh", quiet));

  Failures failures;
  for (std::size_t length = 0; length <= original.size(); ++length) {
    const std::string text = original.substr(0, length);
    failures.record(escaped([&] { mgrl::parseBvh(text, "tiny.bvh", quiet); }), "first " + std::to_string(length) + " bytes");
  }
  std::mt19937_64 rng(kRootSeed);
  for (int i = 0; i < kMutations; ++i) {
    std::string text = original;
    const std::string change = mutate(text, rng);
    failures.record(escaped([&] { mgrl::parseBvh(text, "tiny.bvh", quiet); }),
                    "mutation " + std::to_string(i) + ": " + change);
  }
  CAPTURE(kRootSeed, failures.first);
  CHECK(failures.count == 0);
}

TEST_CASE("asf and amc loaders survive every truncation and seeded byte mutations", "[loader][robustness]") {
  const std::string asfText = mgrl::readFile(mgrl::test::testData() / "tiny.asf");
  const std::string amcText = mgrl::readFile(mgrl::test::testData() / "tiny_01.amc");
  REQUIRE_NOTHROW(parseAsfAndAmc(asfText, amcText));

  Failures failures;
  for (std::size_t length = 0; length <= asfText.size(); ++length) {
    const std::string text = asfText.substr(0, length);
    failures.record(escaped([&] { parseAsfAndAmc(text, amcText); }), "asf: first " + std::to_string(length) + " bytes");
  }
  for (std::size_t length = 0; length <= amcText.size(); ++length) {
    const std::string text = amcText.substr(0, length);
    failures.record(escaped([&] { parseAsfAndAmc(asfText, text); }), "amc: first " + std::to_string(length) + " bytes");
  }
  std::mt19937_64 rng(kRootSeed + 1);
  for (int i = 0; i < kMutations; ++i) {
    std::string asf = asfText, amc = amcText;
    // Alternate which file is corrupted; the other stays valid.
    const bool corruptAsf = i % 2 == 0;
    const std::string change = mutate(corruptAsf ? asf : amc, rng);
    failures.record(escaped([&] { parseAsfAndAmc(asf, amc); }),
                    std::string(corruptAsf ? "asf" : "amc") + " mutation " + std::to_string(i) + ": " + change);
  }
  CAPTURE(kRootSeed, failures.first);
  CHECK(failures.count == 0);
}

}  // namespace robustness_test
