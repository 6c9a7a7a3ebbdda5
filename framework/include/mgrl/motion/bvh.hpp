#pragma once
/// \file
/// BVH (Biovision hierarchy) reading and writing.

#include <iosfwd>
#include <string_view>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/motion.hpp"

namespace mgrl {

/// Largest frame count and joint count a BVH file may declare; larger is treated as
/// corrupt rather than allocated.
constexpr long long kMaxBvhFrames = 10'000'000;
/// The largest frame time a BVH may declare (s): capture runs at 1 fps or faster.
constexpr double kMaxBvhFrameTime_s = 1.0;
constexpr std::size_t kMaxJoints = 4096;

/// Parses BVH text. Accepts any rotation order per joint, position channels on any joint
/// (they replace the offset), End Sites, LF/CRLF/CR line endings and any whitespace, and
/// any positive frame time. Lengths stay in file units (motion_io.hpp converts them).
/// When `Frames:` disagrees with the data lines present, the lines win and `warn` hears
/// about it once. Throws ParseError (`source:line: expected ..., found ...`) on anything
/// malformed: unknown keywords, wrong channel counts, non-numbers, NaN/inf, duplicate joint
/// names, a missing MOTION section, a non-positive frame time, an absurd frame count.
Motion parseBvh(std::string_view text, std::string_view source, const WarningSink& warn = {});
/// Reads the whole stream, then parseBvh().
Motion readBvh(std::istream& in, std::string_view source, const WarningSink& warn = {});

struct BvhWriteOptions {
  /// File length units per metre of the motion (1 writes metres, 100 centimetres).
  double lengthScale = 1.0;
  /// false: principal Euler angles (middle within +-90 degrees, outer within +-180), the
  /// usual BVH form, so a file read and written again keeps its channel values. true: the
  /// solution nearest the previous frame, without 360-degree wraps (smooth curves).
  bool continuousAngles = false;
};

/// Writes a standard BVH of `motion`: the skeleton's joints and channel layout (a joint
/// with one or two rotation channels gets all three), 7 decimals. Reading it back gives the
/// same joint positions.
void writeBvh(std::ostream& out, const Motion& motion, const BvhWriteOptions& options = {});

}  // namespace mgrl
