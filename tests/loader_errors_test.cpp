// Bad input for the BVH and ASF/AMC loaders: every malformed file throws ParseError with
// `source:line: expected ..., found ...` pointing at the right line; and the leniency the
// loaders promise (line endings, whitespace, Frames: disagreement, rotation orders).

#include <string>
#include <string_view>
#include <vector>

#include <catch2/catch.hpp>

#include "mgrl/motion/asf_amc.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/core/error.hpp"
#include "mgrl/core/rotation.hpp"
#include "test_support.hpp"

// A namespace of its own: the suite compiles in unity batches (tests/CMakeLists.txt).
namespace loader_errors_test {

using Catch::Contains;
using mgrl::ParseError;


namespace {

// Three joints, 6 + 3 + 3 = 12 channels, two frames. Line numbers are in the comments the
// tests below refer to.
constexpr std::string_view kBvh =
    "HIERARCHY\n"                                                              // 1
    "ROOT Hips\n"                                                              // 2
    "{\n"                                                                      // 3
    "  OFFSET 0 0 0\n"                                                         // 4
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n"  // 5
    "  JOINT Chest\n"                                                          // 6
    "  {\n"                                                                    // 7
    "    OFFSET 0 10 0\n"                                                      // 8
    "    CHANNELS 3 Zrotation Yrotation Xrotation\n"                           // 9
    "    JOINT Head\n"                                                         // 10
    "    {\n"                                                                  // 11
    "      OFFSET 0 10 0\n"                                                    // 12
    "      CHANNELS 3 Zrotation Yrotation Xrotation\n"                         // 13
    "      End Site\n"                                                         // 14
    "      {\n"                                                                // 15
    "        OFFSET 0 5 0\n"                                                   // 16
    "      }\n"                                                                // 17
    "    }\n"                                                                  // 18
    "  }\n"                                                                    // 19
    "}\n"                                                                      // 20
    "MOTION\n"                                                                 // 21
    "Frames: 2\n"                                                              // 22
    "Frame Time: 0.0333333\n"                                                  // 23
    "0 90 0 0 0 0 0 0 0 0 0 0\n"                                               // 24
    "1 90 0 0 10 0 5 0 0 0 0 -5\n";                                            // 25

// Root with three bones: lfemur (3 dof) -> ltibia (1 dof), and lowerback (3 dof).
constexpr std::string_view kAsf =
    ":version 1.10\n"                // 1
    ":name inline\n"                 // 2
    ":units\n"                       // 3
    "  mass 1.0\n"                   // 4
    "  length 0.45\n"                // 5
    "  angle deg\n"                  // 6
    ":root\n"                        // 7
    "  order TX TY TZ RX RY RZ\n"    // 8
    "  axis XYZ\n"                   // 9
    "  position 0 0 0\n"             // 10
    "  orientation 0 0 0\n"          // 11
    ":bonedata\n"                    // 12
    "  begin\n"                      // 13
    "    id 1\n"                     // 14
    "    name lfemur\n"              // 15
    "    direction 0 -1 0\n"         // 16
    "    length 7\n"                 // 17
    "    axis 0 0 20 XYZ\n"          // 18
    "    dof rx ry rz\n"             // 19
    "  end\n"                        // 20
    "  begin\n"                      // 21
    "    id 2\n"                     // 22
    "    name ltibia\n"              // 23
    "    direction 0 -1 0\n"         // 24
    "    length 8\n"                 // 25
    "    axis 0 0 20 XYZ\n"          // 26
    "    dof rx\n"                   // 27
    "  end\n"                        // 28
    "  begin\n"                      // 29
    "    id 3\n"                     // 30
    "    name lowerback\n"           // 31
    "    direction 0 1 0\n"          // 32
    "    length 2\n"                 // 33
    "    axis 0 0 0 XYZ\n"           // 34
    "    dof rx ry rz\n"             // 35
    "  end\n"                        // 36
    ":hierarchy\n"                   // 37
    "  begin\n"                      // 38
    "    root lfemur lowerback\n"    // 39
    "    lfemur ltibia\n"            // 40
    "  end\n";                       // 41

// Two frames for kAsf.
constexpr std::string_view kAmc =
    ":FULLY-SPECIFIED\n"        // 1
    ":DEGREES\n"                // 2
    "1\n"                       // 3
    "root 0 0 0 0 0 0\n"        // 4
    "lfemur 10 0 0\n"           // 5
    "ltibia 20\n"               // 6
    "lowerback 0 0 0\n"         // 7
    "2\n"                       // 8
    "root 0 0 1 0 0 0\n"        // 9
    "lfemur 12 0 0\n"           // 10
    "ltibia 22\n"               // 11
    "lowerback 0 1 0\n";        // 12

// `text` with its 1-based line `line` replaced by `replacement` (which may hold several
// lines, or none when empty).
std::string withLine(std::string_view text, std::size_t line, std::string_view replacement) {
  std::size_t begin = 0;
  for (std::size_t l = 1; l < line; ++l) begin = text.find('\n', begin) + 1;
  const std::size_t end = text.find('\n', begin);
  std::string result(text.substr(0, begin));
  result += replacement;
  if (!replacement.empty() || end == std::string_view::npos) result += '\n';
  if (end != std::string_view::npos) result += text.substr(end + 1);
  return result;
}

// The first `count` lines of `text`, each with its line break.
std::string firstLines(std::string_view text, std::size_t count) {
  std::size_t end = 0;
  for (std::size_t l = 0; l < count; ++l) end = text.find('\n', end) + 1;
  return std::string(text.substr(0, end));
}

std::string replaceAll(std::string_view text, std::string_view from, std::string_view to) {
  std::string result;
  std::size_t pos = 0;
  for (std::size_t hit; (hit = text.find(from, pos)) != std::string_view::npos; pos = hit + from.size()) {
    result += text.substr(pos, hit - pos);
    result += to;
  }
  result += text.substr(pos);
  return result;
}

mgrl::Motion bvh(std::string_view text) { return mgrl::parseBvh(text, "bad.bvh"); }
mgrl::AsfSkeleton asf(std::string_view text) { return mgrl::parseAsf(text, "bad.asf"); }
mgrl::Motion amc(std::string_view text) { return mgrl::parseAmc(text, "bad.amc", asf(kAsf)); }

// Same skeleton and the same frames, value for value.
void requireSameMotion(const mgrl::Motion& a, const mgrl::Motion& b) {
  REQUIRE(a.skeleton().jointCount() == b.skeleton().jointCount());
  for (std::size_t j = 0; j < a.skeleton().jointCount(); ++j) {
    const mgrl::Joint& ja = a.skeleton().joint(j);
    const mgrl::Joint& jb = b.skeleton().joint(j);
    CHECK(ja.name == jb.name);
    CHECK(ja.parent == jb.parent);
    CHECK(ja.offset == jb.offset);
    CHECK(ja.channels == jb.channels);
    CHECK(ja.endSite.has_value() == jb.endSite.has_value());
    if (ja.endSite && jb.endSite) CHECK(*ja.endSite == *jb.endSite);
  }
  REQUIRE(a.frameCount() == b.frameCount());
  CHECK(a.frameTime() == b.frameTime());
  for (std::size_t f = 0; f < a.frameCount(); ++f) {
    for (std::size_t j = 0; j < a.skeleton().jointCount(); ++j) {
      CHECK(a.rotation(f, j).coeffs() == b.rotation(f, j).coeffs());
      CHECK(a.localTranslation(f, j) == b.localTranslation(f, j));
    }
  }
}

}  // namespace

TEST_CASE("the inline fixtures used by the error tests are valid", "[loader][errors]") {
  const mgrl::Motion motion = bvh(kBvh);
  CHECK(motion.skeleton().jointCount() == 3);
  CHECK(motion.frameCount() == 2);
  const mgrl::Motion acclaim = amc(kAmc);
  CHECK(acclaim.skeleton().jointCount() == 4);
  CHECK(acclaim.frameCount() == 2);
}

// ---------------------------------------------------------------------------------------
// BVH

TEST_CASE("bvh reports a file truncated in the hierarchy at its last line", "[loader][errors]") {
  {
    INFO("ends after an OFFSET, with its line break");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 12)),
                        "bad.bvh:12: expected OFFSET, CHANNELS, JOINT, End Site or '}', found end of file");
  }
  {
    INFO("ends in the middle of a CHANNELS line");
    const std::string text = firstLines(kBvh, 8) + "    CHANNELS 3 Zrotation";
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:9: expected 3 channel names");
  }
  {
    INFO("ends in the middle of an OFFSET");
    const std::string text = firstLines(kBvh, 7) + "    OFFSET 0 10";
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:8: expected 3 OFFSET coordinates");
  }
  {
    INFO("ends inside End Site");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 15)), "bad.bvh:15: expected 'OFFSET', found end of file");
  }
  {
    INFO("ends after the root's name");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 2)), "bad.bvh:2: expected '{', found end of file");
  }
  {
    INFO("trailing blank lines do not move the reported line");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 12) + "\n\n  \n"), "bad.bvh:12: expected OFFSET, CHANNELS");
  }
  {
    INFO("empty file");
    REQUIRE_PARSE_ERROR(bvh(""), "bad.bvh:1: expected 'HIERARCHY', found end of file");
  }
}

TEST_CASE("bvh reports a file truncated in the frame data", "[loader][errors]") {
  {
    INFO("cut in the middle of the last data line");
    const std::string text = firstLines(kBvh, 24) + "1 90 0 0 10";
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:25: expected 12 channel values, found 5");
  }
  {
    INFO("cut inside a number: the frame just has fewer values");
    const std::string text = firstLines(kBvh, 24) + "1 90 0 0 10 0 5 0 0 0 0 -";
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:25: expected a number, found '-'");
  }
  {
    INFO("cut after Frame Time: no frames at all");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 23)),
                        "bad.bvh:23: expected at least one frame of channel values, found end of file");
  }
  {
    INFO("cut after Frames:");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 22)), "bad.bvh:22: expected 'Frame', found end of file");
  }
}

TEST_CASE("bvh names the expected and found channel value counts of a data line", "[loader][errors]") {
  {
    INFO("one value short");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 25, "1 90 0 0 10 0 5 0 0 0 0")),
                        "bad.bvh:25: expected 12 channel values, found 11");
  }
  {
    INFO("one value too many");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 90 0 0 0 0 0 0 0 0 0 0 7")),
                        "bad.bvh:24: expected 12 channel values, found 13");
  }
  {
    INFO("a frame split over two lines");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 90 0 0 0 0\n0 0 0 0 0 0")),
                        "bad.bvh:24: expected 12 channel values, found 6");
  }
}

TEST_CASE("bvh reports a CHANNELS line that does not match its count", "[loader][errors]") {
  {
    INFO("fewer names than the count: reported on the CHANNELS line");
    REQUIRE_THROWS_AS(bvh(withLine(kBvh, 9, "    CHANNELS 3 Zrotation Yrotation")), ParseError);
    REQUIRE_THROWS_WITH(bvh(withLine(kBvh, 9, "    CHANNELS 3 Zrotation Yrotation")),
                        Contains("bad.bvh:9: expected 3 channel names") &&
                            Contains("found 2, then 'JOINT' on line 10"));
  }
  {
    INFO("fewer names than the count before an End Site");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 13, "      CHANNELS 2 Zrotation")),
                        "bad.bvh:13: expected 2 channel names (Xposition ... Zrotation), found 1, then 'End' on line 14");
  }
  {
    INFO("an unknown channel name on the line");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 9, "    CHANNELS 3 Zrotation Wrotation Xrotation")),
                        "bad.bvh:9: expected 3 channel names (Xposition ... Zrotation), found 'Wrotation'");
  }
  {
    INFO("a channel named twice");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 9, "    CHANNELS 3 Zrotation Zrotation Xrotation")),
                        "bad.bvh:9: expected each channel once, found 'Zrotation' twice");
  }
  {
    INFO("more than six channels");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 9, "    CHANNELS 7 Zrotation Yrotation Xrotation")),
                        "bad.bvh:9: expected a channel count between 0 and 6, found '7'");
  }
  {
    INFO("a count that is not a number");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 9, "    CHANNELS Zrotation Yrotation Xrotation")),
                        "bad.bvh:9: expected a channel count, found 'Zrotation'");
  }
  {
    INFO("a second CHANNELS line");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 9, "    CHANNELS 1 Zrotation\n    CHANNELS 2 Yrotation Xrotation")),
                        "bad.bvh:10: expected one CHANNELS line per joint, found a second CHANNELS");
  }
  {
    INFO("no channels anywhere");
    const std::string text =
        withLine(withLine(withLine(kBvh, 13, ""), 9, ""), 5, "");  // lines shift up by one each
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:17: expected at least one channel in the hierarchy, found none");
  }
}

TEST_CASE("bvh rejects channel values that are not numbers", "[loader][errors]") {
  {
    INFO("a word");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 90 0 0 abc 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a number, found 'abc'");
  }
  {
    INFO("a number with trailing garbage");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 25, "1 90 0 0 10 0 5 0 0 0 0 -5x")),
                        "bad.bvh:25: expected a number, found '-5x'");
  }
  {
    INFO("a decimal comma");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 90,5 0 0 0 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a number, found '90,5'");
  }
  {
    INFO("a control byte, shown escaped");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, std::string("0 90 0 0 0 0 0 0 0 0 0 \x01"))),
                        "bad.bvh:24: expected a number, found '\\x01'");
  }
  {
    INFO("an explicit plus sign is a number");
    CHECK_NOTHROW(bvh(withLine(kBvh, 24, "+0 +90 0 0 0 0 0 0 0 0 0 0")));
  }
}

TEST_CASE("bvh rejects NaN and infinite channel values", "[loader][errors]") {
  {
    INFO("nan");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 90 0 0 nan 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a finite number, found 'nan'");
  }
  {
    INFO("NaN, any case");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 25, "1 90 0 0 10 0 5 0 0 0 0 NaN")),
                        "bad.bvh:25: expected a finite number, found 'NaN'");
  }
  {
    INFO("inf");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "inf 90 0 0 0 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a finite number, found 'inf'");
  }
  {
    INFO("-infinity");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 -infinity 0 0 0 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a finite number, found '-infinity'");
  }
  {
    INFO("a number too large for a double");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 24, "0 1e999 0 0 0 0 0 0 0 0 0 0")),
                        "bad.bvh:24: expected a finite number, found '1e999'");
  }
  {
    INFO("nan in an OFFSET");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    OFFSET 0 nan 0")),
                        "bad.bvh:8: expected a finite number, found 'nan'");
  }
}

TEST_CASE("bvh rejects unknown keywords in the hierarchy", "[loader][errors]") {
  {
    INFO("an unknown keyword inside a joint");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    ROTATION 0 0 0")),
                        "bad.bvh:8: expected OFFSET, CHANNELS, JOINT, End Site or '}', found 'ROTATION'");
  }
  {
    INFO("keywords are case-sensitive");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 10, "    joint Head")),
                        "bad.bvh:10: expected OFFSET, CHANNELS, JOINT, End Site or '}', found 'joint'");
  }
  {
    INFO("End without Site");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 14, "      End Point")), "bad.bvh:14: expected 'Site', found 'Point'");
  }
  {
    INFO("no HIERARCHY");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 1, "SKELETON")), "bad.bvh:1: expected 'HIERARCHY', found 'SKELETON'");
  }
  {
    INFO("JOINT where ROOT belongs");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 2, "JOINT Hips")), "bad.bvh:2: expected 'ROOT', found 'JOINT'");
  }
  {
    INFO("a second ROOT after the first closes");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 21, "ROOT Other\nMOTION")), "bad.bvh:21: expected 'MOTION', found 'ROOT'");
  }
  {
    INFO("a joint without a name");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 10, "    JOINT")), "bad.bvh:10: expected a joint name, found end of line");
  }
  {
    INFO("a second OFFSET");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    OFFSET 0 10 0\n    OFFSET 0 10 0")),
                        "bad.bvh:9: expected one OFFSET per joint, found a second OFFSET");
  }
  {
    INFO("a second End Site");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 17, "      }\n      End Site { OFFSET 0 1 0 }")),
                        "bad.bvh:18: expected one End Site per joint, found a second End Site");
  }
  {
    INFO("text after the Frame Time");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: 0.0333333 fps")),
                        "bad.bvh:23: expected the end of the Frame Time line, found 'fps'");
  }
}

TEST_CASE("bvh rejects duplicate joint names and says where the first one is", "[loader][errors]") {
  {
    INFO("a child named like its parent");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 10, "    JOINT Chest")),
                        "bad.bvh:10: expected a unique joint name, found 'Chest' again (first on line 6)");
  }
  {
    INFO("a joint named like the root");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 10, "    JOINT Hips")),
                        "bad.bvh:10: expected a unique joint name, found 'Hips' again (first on line 2)");
  }
}

TEST_CASE("bvh requires a MOTION section", "[loader][errors]") {
  {
    INFO("the file ends after the hierarchy");
    REQUIRE_PARSE_ERROR(bvh(firstLines(kBvh, 20)), "bad.bvh:20: expected 'MOTION', found end of file");
  }
  {
    INFO("Frames: without MOTION");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 21, "")), "bad.bvh:21: expected 'MOTION', found 'Frames:'");
  }
  {
    INFO("MOTION without Frames:");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 22, "")), "bad.bvh:22: expected 'Frames:', found 'Frame'");
  }
}

TEST_CASE("bvh rejects a frame time that is not positive", "[loader][errors]") {
  {
    INFO("zero");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: 0")),
                        "bad.bvh:23: expected a positive frame time, found 0");
  }
  {
    INFO("negative");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: -0.01")),
                        "bad.bvh:23: expected a positive frame time, found -0.01");
  }
  {
    INFO("negative zero");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: -0")),
                        "bad.bvh:23: expected a positive frame time, found -0");
  }
  {
    INFO("not a number");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: fast")),
                        "bad.bvh:23: expected a frame time, found 'fast'");
  }
  {
    INFO("nan");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 23, "Frame Time: nan")),
                        "bad.bvh:23: expected a finite number, found 'nan'");
  }
}

TEST_CASE("bvh rejects an absurd or malformed frame count", "[loader][errors]") {
  {
    INFO("eleven digits");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 22, "Frames: 99999999999")),
                        "bad.bvh:22: expected a frame count between 0 and 10000000, found '99999999999'");
  }
  {
    INFO("beyond 64 bits");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 22, "Frames: 99999999999999999999999")),
                        "bad.bvh:22: expected a frame count between 0 and 10000000, found '99999999999999999999999'");
  }
  {
    INFO("negative");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 22, "Frames: -2")),
                        "bad.bvh:22: expected a frame count between 0 and 10000000, found '-2'");
  }
  {
    INFO("not an integer");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 22, "Frames: 2.5")), "bad.bvh:22: expected a frame count, found '2.5'");
  }
  {
    INFO("the largest allowed count with two lines present: no huge allocation, a warning");
    int warnings = 0;
    const mgrl::Motion motion =
        mgrl::parseBvh(withLine(kBvh, 22, "Frames: 10000000"), "big.bvh", [&](const std::string&) { ++warnings; });
    CHECK(motion.frameCount() == 2);
    CHECK(warnings == 1);
  }
}

TEST_CASE("bvh allocates for the frames present, not for the frames the header claims", "[loader][errors]") {
  // 4000 joints of 6 channels: reserving the claimed 10 million frames up front would ask
  // for terabytes and throw std::bad_alloc (or abort under ASan).
  const int depth = 4000;
  std::string text = "HIERARCHY\nROOT J0 {\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
  for (int j = 1; j < depth; ++j)
    text += "JOINT J" + std::to_string(j) + " {\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n";
  for (int j = 0; j < depth; ++j) text += "}\n";
  text += "MOTION\nFrames: 10000000\nFrame Time: 0.01\n";
  for (int v = 0; v < depth * 6; ++v) text += "0 ";
  text += "\n";
  int warnings = 0;
  const mgrl::Motion motion = mgrl::parseBvh(text, "wide.bvh", [&](const std::string&) { ++warnings; });
  CHECK(motion.frameCount() == 1);
  CHECK(warnings == 1);
}

TEST_CASE("bvh rejects a malformed OFFSET", "[loader][errors]") {
  {
    INFO("a word for a coordinate");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    OFFSET 0 ten 0")),
                        "bad.bvh:8: expected an OFFSET coordinate, found 'ten'");
  }
  {
    INFO("two coordinates: reported on the OFFSET line");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    OFFSET 0 10")),
                        "bad.bvh:8: expected 3 OFFSET coordinates, found 2, then 'CHANNELS' on line 9");
  }
  {
    INFO("four coordinates");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 8, "    OFFSET 0 10 0 0")),
                        "bad.bvh:8: expected OFFSET, CHANNELS, JOINT, End Site or '}', found '0'");
  }
  {
    INFO("a bad End Site OFFSET");
    REQUIRE_PARSE_ERROR(bvh(withLine(kBvh, 16, "        OFFSET 0 5")),
                        "bad.bvh:16: expected 3 OFFSET coordinates, found 2, then '}' on line 17");
  }
}

TEST_CASE("bvh nesting beyond the joint limit is an error, not a stack overflow", "[loader][errors]") {
  {
    INFO("100000 nested joints");
    std::string text = "HIERARCHY\nROOT J0 {\n";
    for (int j = 1; j < 100000; ++j) text += "JOINT J" + std::to_string(j) + " {\n";
    // Joint 4096 (the 4097th) opens on line 4096 + 2.
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:4098: expected at most 4096 joints, found more");
  }
  {
    INFO("100000 nested braces");
    std::string text = "HIERARCHY\nROOT Hips\n{\n";
    for (int j = 0; j < 100000; ++j) text += "{\n";
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:4: expected OFFSET, CHANNELS, JOINT, End Site or '}', found '{'");
  }
  {
    INFO("100000 braces in one token");
    const std::string text = "HIERARCHY\nROOT Hips\n{\n" + std::string(100000, '{');
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:4: expected OFFSET, CHANNELS, JOINT, End Site or '}', found '{{{{");
  }
  {
    INFO("100000 closing braces");
    const std::string text = firstLines(kBvh, 20) + std::string(100000, '}');
    REQUIRE_PARSE_ERROR(bvh(text), "bad.bvh:21: expected 'MOTION', found '}}}}");
  }
}

TEST_CASE("bvh reads a chain nested 4000 deep", "[loader][errors]") {
  const int depth = 4000;
  std::string text = "HIERARCHY\nROOT J0 {\nOFFSET 0 0 0\nCHANNELS 1 Zrotation\n";
  for (int j = 1; j < depth; ++j) text += "JOINT J" + std::to_string(j) + " {\nOFFSET 0 1 0\n";
  for (int j = 0; j < depth; ++j) text += "}\n";
  text += "MOTION\nFrames: 1\nFrame Time: 0.01\n45\n";
  const mgrl::Motion motion = bvh(text);
  CHECK(motion.skeleton().jointCount() == static_cast<std::size_t>(depth));
  CHECK(motion.skeleton().joint(depth - 1).parent == depth - 2);
}

// ---------------------------------------------------------------------------------------
// BVH leniency

TEST_CASE("bvh reads CRLF, lone CR, tabs and extra spaces like LF", "[loader][errors]") {
  const mgrl::Motion reference = bvh(kBvh);
  {
    INFO("CRLF");
    requireSameMotion(bvh(replaceAll(kBvh, "\n", "\r\n")), reference);
  }
  {
    INFO("lone CR");
    requireSameMotion(bvh(replaceAll(kBvh, "\n", "\r")), reference);
  }
  {
    INFO("tabs and runs of spaces between tokens, trailing blanks");
    requireSameMotion(bvh(replaceAll(replaceAll(kBvh, " ", " \t  "), "\n", " \t\n")), reference);
  }
  {
    INFO("indentation by tabs, CRLF, no final line break");
    std::string text = replaceAll(replaceAll(kBvh, "  ", "\t"), "\n", "\r\n");
    text.resize(text.size() - 2);
    requireSameMotion(bvh(text), reference);
  }
  {
    INFO("errors in a CRLF file are on the same line as in LF");
    REQUIRE_PARSE_ERROR(bvh(replaceAll(withLine(kBvh, 25, "1 90 0 0 10 0 5 0 0 0 0"), "\n", "\r\n")),
                        "bad.bvh:25: expected 12 channel values, found 11");
  }
  {
    INFO("errors in a lone-CR file are on the same line as in LF");
    REQUIRE_PARSE_ERROR(bvh(replaceAll(withLine(kBvh, 25, "1 90 0 0 10 0 5 0 0 0 0"), "\n", "\r")),
                        "bad.bvh:25: expected 12 channel values, found 11");
  }
}

TEST_CASE("bvh uses the data lines present when the frame count disagrees and warns once", "[loader][errors]") {
  std::vector<std::string> warnings;
  const mgrl::WarningSink warn = [&](const std::string& message) { warnings.push_back(message); };
  {
    INFO("Frames: says more");
    warnings.clear();
    const mgrl::Motion motion = mgrl::parseBvh(withLine(kBvh, 22, "Frames: 5"), "short.bvh", warn);
    CHECK(motion.frameCount() == 2);
    REQUIRE(warnings.size() == 1);
    CHECK_THAT(warnings[0], Contains("short.bvh") && Contains("5") && Contains("2"));
  }
  {
    INFO("Frames: says fewer");
    warnings.clear();
    const mgrl::Motion motion = mgrl::parseBvh(withLine(kBvh, 22, "Frames: 1"), "long.bvh", warn);
    CHECK(motion.frameCount() == 2);
    CHECK(warnings.size() == 1);
  }
  {
    INFO("Frames: says zero");
    warnings.clear();
    const mgrl::Motion motion = mgrl::parseBvh(withLine(kBvh, 22, "Frames: 0"), "zero.bvh", warn);
    CHECK(motion.frameCount() == 2);
    CHECK(warnings.size() == 1);
  }
  {
    INFO("Frames: agrees: no warning");
    warnings.clear();
    mgrl::parseBvh(kBvh, "ok.bvh", warn);
    CHECK(warnings.empty());
  }
  {
    INFO("no sink: no warning, no crash");
    CHECK(mgrl::parseBvh(withLine(kBvh, 22, "Frames: 5"), "short.bvh").frameCount() == 2);
  }
}

TEST_CASE("bvh accepts trailing and interleaved blank lines after the data", "[loader][errors]") {
  int warnings = 0;
  const mgrl::WarningSink warn = [&](const std::string&) { ++warnings; };
  {
    INFO("trailing blank lines");
    std::string text(kBvh);  // appended, not `+`: see "a second :hierarchy" below
    text.append("\n\n  \n\t\n");
    requireSameMotion(mgrl::parseBvh(text, "blank.bvh", warn), bvh(kBvh));
  }
  {
    INFO("trailing blank lines with CRLF");
    std::string text(kBvh);
    text.append("\n\n");
    requireSameMotion(mgrl::parseBvh(replaceAll(text, "\n", "\r\n"), "blank.bvh", warn), bvh(kBvh));
  }
  CHECK(warnings == 0);
}

TEST_CASE("bvh position channels on a non-root joint replace its offset", "[loader][errors]") {
  {
    INFO("all three axes");
    const mgrl::Motion motion = bvh(withLine(kBvh, 9, "    CHANNELS 3 Xposition Yposition Zposition"));
    const mgrl::Skeleton& skeleton = motion.skeleton();
    const auto chest = static_cast<std::size_t>(skeleton.find("Chest"));
    CHECK(skeleton.translationSlot(chest) >= 0);
    CHECK(motion.localTranslation(0, chest) == Eigen::Vector3d(0, 0, 0));
    CHECK(motion.localTranslation(1, chest) == Eigen::Vector3d(5, 0, 0));
    CHECK(motion.rotation(1, chest).coeffs() == Eigen::Quaterniond::Identity().coeffs());
  }
}

TEST_CASE("bvh position channels on one axis of a non-root joint keep the other offset axes",
          "[loader][errors]") {
  const std::string text = withLine(withLine(withLine(kBvh, 25, "1 90 0 0 10 0 7 0 0 0 0 0 -5"), 24,
                                             "0 90 0 0 0 0 3 0 0 0 0 0 0"),
                                    9, "    CHANNELS 4 Yposition Zrotation Yrotation Xrotation");
  const mgrl::Motion motion = bvh(text);
  const auto chest = static_cast<std::size_t>(motion.skeleton().find("Chest"));
  CHECK(motion.localTranslation(0, chest) == Eigen::Vector3d(0, 3, 0));
  CHECK(motion.localTranslation(1, chest) == Eigen::Vector3d(0, 7, 0));
  // Offset (0, 10, 0): X and Z come from it, Y from the channel.
  const std::string shifted = withLine(text, 8, "    OFFSET 4 10 6");
  CHECK(bvh(shifted).localTranslation(1, chest) == Eigen::Vector3d(4, 7, 6));
}

TEST_CASE("bvh composes rotation channels in the order they are listed", "[loader][errors]") {
  using mgrl::Axis;
  const auto rad = [](double degrees) { return degrees * mgrl::kDegToRad; };
  // Head's channels are the last three values of each frame: 10, 20, 30 degrees.
  const std::string values = "1 90 0 0 10 0 5 0 0 10 20 30";
  struct Case {
    const char* channels;
    std::array<Axis, 3> order;
  };
  for (const Case& c : {Case{"Xrotation Zrotation Yrotation", {Axis::X, Axis::Z, Axis::Y}},
                        Case{"Zrotation Yrotation Xrotation", {Axis::Z, Axis::Y, Axis::X}},
                        Case{"Yrotation Xrotation Zrotation", {Axis::Y, Axis::X, Axis::Z}},
                        Case{"xrotation yrotation zrotation", {Axis::X, Axis::Y, Axis::Z}}}) {
    CAPTURE(c.channels);
    const mgrl::Motion motion =
        bvh(withLine(withLine(kBvh, 25, values), 13, std::string("      CHANNELS 3 ") + c.channels));
    const auto head = static_cast<std::size_t>(motion.skeleton().find("Head"));
    const Eigen::Quaterniond expected = mgrl::axisRotation(c.order[0], rad(10)) *
                                        mgrl::axisRotation(c.order[1], rad(20)) *
                                        mgrl::axisRotation(c.order[2], rad(30));
    CHECK(motion.rotation(1, head).isApprox(expected, 1e-12));
    // The reverse order is a different rotation for these angles: the order matters.
    const Eigen::Quaterniond reversed = mgrl::axisRotation(c.order[2], rad(30)) *
                                        mgrl::axisRotation(c.order[1], rad(20)) *
                                        mgrl::axisRotation(c.order[0], rad(10));
    CHECK_FALSE(motion.rotation(1, head).isApprox(reversed, 1e-6));
  }
}

// ---------------------------------------------------------------------------------------
// ASF

TEST_CASE("asf rejects hierarchy cycles", "[loader][errors]") {
  {
    INFO("a b / b a: reported on the line closing the cycle");
    REQUIRE_PARSE_ERROR(asf(withLine(withLine(kAsf, 40, "    lfemur ltibia\n    ltibia lfemur"), 39,
                                     "    root lowerback")),
                        "bad.asf:41: expected a tree rooted at root, found a cycle through 'lfemur'");
  }
  {
    INFO("a bone its own parent");
    REQUIRE_PARSE_ERROR(asf(withLine(withLine(kAsf, 40, "    lfemur ltibia\n    lowerback lowerback"), 39,
                                     "    root lfemur")),
                        "bad.asf:41: expected a tree rooted at root, found a cycle through 'lowerback'");
  }
  {
    INFO("root listed as a child");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur ltibia root")),
                        "bad.asf:40: expected a tree rooted at root, found a cycle: root listed as a child of 'lfemur'");
  }
  {
    INFO("root its own child");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 39, "    root root lfemur lowerback")),
                        "bad.asf:39: expected a tree rooted at root, found a cycle: root listed as a child of 'root'");
  }
}

TEST_CASE("asf rejects a bone with two parents", "[loader][errors]") {
  {
    INFO("on a later line");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur ltibia\n    lowerback ltibia")),
                        "bad.asf:41: expected one parent per bone, found 'ltibia' given a second parent 'lowerback'");
  }
  {
    INFO("on the same line");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur ltibia ltibia")),
                        "bad.asf:40: expected one parent per bone, found 'ltibia' given a second parent 'lfemur'");
  }
  {
    INFO("a child of root listed again under a bone");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur ltibia lowerback")),
                        "bad.asf:40: expected one parent per bone, found 'lowerback' given a second parent 'lfemur'");
  }
}

TEST_CASE("asf rejects unknown and missing bones in the hierarchy", "[loader][errors]") {
  {
    INFO("an unknown child");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur lknee")),
                        "bad.asf:40: expected a bone defined in :bonedata, found 'lknee'");
  }
  {
    INFO("an unknown parent");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lknee ltibia")),
                        "bad.asf:40: expected a bone defined in :bonedata, found 'lknee'");
  }
  {
    INFO("a parent without children");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "    lfemur")),
                        "bad.asf:40: expected a parent followed by its children, found a line with one name");
  }
  {
    INFO("a bone missing: reported at its name in :bonedata");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 40, "")),
                        "bad.asf:23: expected every bone in :hierarchy, found 'ltibia' missing from it");
  }
  {
    INFO("no 'end' of the hierarchy");
    REQUIRE_PARSE_ERROR(asf(firstLines(kAsf, 40)), "bad.asf:40: expected 'end' of the hierarchy, found end of file");
  }
}

TEST_CASE("asf rejects unknown section keywords and misplaced sections", "[loader][errors]") {
  {
    INFO("an unknown section");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 7, ":skin\n:root")),
                        "bad.asf:7: expected :version, :name, :units, :documentation, :root, :bonedata or "
                        ":hierarchy, found ':skin'");
  }
  {
    INFO("an unknown keyword in :root");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 9, "  axes XYZ")),
                        "bad.asf:9: expected order, axis, position or orientation, found 'axes'");
  }
  {
    INFO("an unknown keyword in a bone");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 17, "    size 7")),
                        "bad.asf:17: expected id, name, direction, length, axis, dof, limits or end, found 'size'");
  }
  {
    INFO("an unknown unit");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 6, "  angle grad")), "bad.asf:6: expected deg or rad, found 'grad'");
  }
  {
    INFO(":bonedata after an empty :hierarchy");
    const std::string text = firstLines(kAsf, 11) + ":hierarchy\n  begin\n  end\n" +
                             std::string(kAsf.substr(firstLines(kAsf, 11).size(),
                                                     firstLines(kAsf, 36).size() - firstLines(kAsf, 11).size()));
    REQUIRE_PARSE_ERROR(asf(text), "bad.asf:15: expected :bonedata before :hierarchy, found ':bonedata' after it");
  }
  {
    INFO("a second :hierarchy");
    // Appended rather than `std::string(kAsf) + "..."`: g++ 12 at -O1 takes the temporary's
    // small-string buffer for the whole text and warns (-Warray-bounds), wrongly.
    std::string text(kAsf);
    text.append(":hierarchy\n  begin\n    root lfemur\n  end\n");
    REQUIRE_PARSE_ERROR(asf(text), "bad.asf:42: expected one :hierarchy section, found a second ':hierarchy'");
  }
  {
    INFO("no :hierarchy");
    REQUIRE_PARSE_ERROR(asf(firstLines(kAsf, 36)), "bad.asf:36: expected a :hierarchy section, found end of file");
  }
  {
    INFO("a bone without 'end'");
    REQUIRE_PARSE_ERROR(asf(firstLines(kAsf, 26)), "bad.asf:26: expected 'end' of the bone, found end of file");
  }
}

TEST_CASE("asf rejects bad degree-of-freedom names", "[loader][errors]") {
  {
    INFO("an unknown name");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 27, "    dof rq")),
                        "bad.asf:27: expected rotational degrees of freedom rx, ry, rz, each once, found 'rq'");
  }
  {
    INFO("a translation on a bone");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 27, "    dof rx tx")),
                        "bad.asf:27: expected rotational degrees of freedom rx, ry, rz, each once, found 'tx'");
  }
  {
    INFO("a repeated name");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 19, "    dof rx ry rx")),
                        "bad.asf:19: expected rotational degrees of freedom rx, ry, rz, each once, found 'rx'");
  }
  {
    INFO("a bad root order");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 8, "  order TX TY TZ RX RY RW")),
                        "bad.asf:8: expected root order channels TX TY TZ RX RY RZ, each once, found 'RW'");
  }
  {
    INFO("a bad axis order");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 26, "    axis 0 0 20 XYX")),
                        "bad.asf:26: expected an axis order such as XYZ, found 'XYX'");
  }
}

TEST_CASE("asf rejects duplicate bone names and bad numbers", "[loader][errors]") {
  {
    INFO("a duplicate name, reported at the second");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 31, "    name lfemur")),
                        "bad.asf:31: expected a unique bone name, found 'lfemur' again");
  }
  {
    INFO("a bone called root");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 31, "    name root")),
                        "bad.asf:31: expected a bone name other than root, found 'root'");
  }
  {
    INFO("a negative length");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 25, "    length -8")),
                        "bad.asf:25: expected a non-negative bone length, found -8");
  }
  {
    INFO("nan in a direction");
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 24, "    direction 0 nan 0")),
                        "bad.asf:24: expected a finite number, found 'nan'");
  }
}

TEST_CASE("asf reads CRLF and lone CR like LF", "[loader][errors]") {
  const mgrl::AsfSkeleton reference = asf(kAsf);
  for (std::string_view ending : {"\r\n", "\r"}) {
    CAPTURE(ending.size());
    const std::string skeletonText = replaceAll(kAsf, "\n", ending);
    const mgrl::AsfSkeleton converted = asf(skeletonText);
    REQUIRE(converted.skeleton->jointCount() == reference.skeleton->jointCount());
    for (std::size_t j = 0; j < reference.skeleton->jointCount(); ++j) {
      CHECK(converted.skeleton->joint(j).name == reference.skeleton->joint(j).name);
      CHECK(converted.bones[j].dofs == reference.bones[j].dofs);
    }
    requireSameMotion(mgrl::parseAmc(replaceAll(kAmc, "\n", ending), "crlf.amc", converted), amc(kAmc));
  }
}

// ---------------------------------------------------------------------------------------
// AMC

TEST_CASE("amc rejects a bone the skeleton does not have", "[loader][errors]") {
  REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 6, "lknee 20")), "bad.amc:6: expected a bone of the skeleton, found 'lknee'");
}

TEST_CASE("amc names the expected and found value counts of a bone", "[loader][errors]") {
  {
    INFO("too many for a one-dof bone");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 6, "ltibia 20 5")),
                        "bad.amc:6: expected 1 value for bone 'ltibia', found 2");
  }
  {
    INFO("too few for a three-dof bone");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 10, "lfemur 12 0")),
                        "bad.amc:10: expected 3 values for bone 'lfemur', found 2");
  }
  {
    INFO("none for the root");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 4, "root")), "bad.amc:4: expected 6 values for bone 'root', found 0");
  }
}

TEST_CASE("amc rejects a frame missing a bone", "[loader][errors]") {
  {
    INFO("file truncated inside the last frame");
    REQUIRE_PARSE_ERROR(amc(firstLines(kAmc, 11)),
                        "bad.amc:11: expected values for bone 'lowerback' in frame 2, found end of file");
  }
  {
    INFO("file truncated after a frame number");
    REQUIRE_PARSE_ERROR(amc(firstLines(kAmc, 8)),
                        "bad.amc:8: expected values for bone 'root' in frame 2, found end of file");
  }
  {
    INFO("a bone missing from a middle frame");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 7, "")),
                        "bad.amc:7: expected values for bone 'lowerback' in frame 1, found frame 2 starting");
  }
  {
    INFO("a bone given twice");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 7, "ltibia 21")), "bad.amc:7: expected bone 'ltibia' once per frame, found it again");
  }
  {
    INFO("no frames");
    REQUIRE_PARSE_ERROR(amc(firstLines(kAmc, 2)), "bad.amc:2: expected at least one frame, found end of file");
  }
}

TEST_CASE("amc rejects values that are not finite numbers", "[loader][errors]") {
  {
    INFO("a word");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 5, "lfemur 10 abc 0")), "bad.amc:5: expected a number, found 'abc'");
  }
  {
    INFO("NaN");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 6, "ltibia NaN")), "bad.amc:6: expected a finite number, found 'NaN'");
  }
  {
    INFO("inf in the root translation");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 9, "root 0 inf 1 0 0 0")),
                        "bad.amc:9: expected a finite number, found 'inf'");
  }
}

TEST_CASE("amc rejects bone lines before the first frame number", "[loader][errors]") {
  {
    INFO("the frame number missing");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 3, "")), "bad.amc:3: expected a frame number, found 'root'");
  }
  {
    INFO("an unknown header keyword");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 2, ":GRADIANS")),
                        "bad.amc:2: expected :FULLY-SPECIFIED, :DEGREES, :RADIANS or a frame number, found ':GRADIANS'");
  }
  {
    INFO("frame numbers going backwards");
    REQUIRE_PARSE_ERROR(amc(withLine(kAmc, 8, "1")), "bad.amc:8: expected a frame number after 1, found '1'");
  }
}

// A length unit no skeleton has is refused at its line, instead of a skeleton
// nanometres or millions of metres tall (1e-320 gave height null and ground at 1e300 m).
TEST_CASE("asf rejects an implausible length unit", "[loader][errors]") {
  for (const auto& [unit, shown] : {std::pair{"1e-320", "1e-320"}, std::pair{"1e-9", "1e-09"}, std::pair{"5000", "5000"}}) {
    CAPTURE(unit);
    REQUIRE_PARSE_ERROR(asf(withLine(kAsf, 5, std::string("  length ") + unit)),
                        std::string("bad.asf:5: expected a length unit in [0.001, 1000] (CMU: 0.45), found ") + shown);
  }
  CHECK_NOTHROW(asf(withLine(kAsf, 5, "  length 1")));
}

}  // namespace loader_errors_test
