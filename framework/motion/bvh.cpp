#include "mgrl/motion/bvh.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <istream>
#include <ostream>
#include <unordered_map>

#include <fmt/format.h>

#include "mgrl/core/text_scanner.hpp"

namespace mgrl {
namespace {

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

bool equalsIgnoreCase(std::string_view a, std::string_view b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](char x, char y) {
           return std::tolower(static_cast<unsigned char>(x)) == std::tolower(static_cast<unsigned char>(y));
         });
}

bool parseChannel(std::string_view token, Channel& channel) {
  static constexpr std::string_view kNames[] = {"Xposition", "Yposition", "Zposition",
                                                "Xrotation", "Yrotation", "Zrotation"};
  for (int i = 0; i < 6; ++i) {
    if (equalsIgnoreCase(token, kNames[i])) {
      channel = {i < 3 ? Channel::Kind::Position : Channel::Kind::Rotation, static_cast<Axis>(i % 3)};
      return true;
    }
  }
  return false;
}

struct HierarchyParser {
  TextScanner& in;
  std::vector<Joint> joints;
  std::unordered_map<std::string, std::size_t> lineOfName;

  // Reads the joint name after ROOT/JOINT (rest of the line; names may hold spaces) and
  // the opening brace, which may sit on the same line.
  void openJoint(int parent) {
    in.skipBlanks();
    std::string_view name = trim(in.nextLine());
    bool braceOnLine = false;
    if (!name.empty() && name.back() == '{') {
      braceOnLine = true;
      name = trim(name.substr(0, name.size() - 1));
    }
    if (name.empty()) in.fail("a joint name", "end of line");
    if (joints.size() >= kMaxJoints)
      in.fail(fmt::format("at most {} joints", kMaxJoints), "more");
    if (auto [it, fresh] = lineOfName.emplace(std::string(name), in.line()); !fresh)
      in.fail("a unique joint name", fmt::format("{} again (first on line {})", quoteToken(name), it->second));
    if (!braceOnLine) in.expect("{");
    Joint joint;
    joint.name = std::string(name);
    joint.parent = parent;
    joints.push_back(std::move(joint));
  }

  // A list cut short (OFFSET coordinates, CHANNELS names) is a fault of the keyword's line,
  // not of the line where the next keyword happens to sit.
  [[noreturn]] void failShort(std::size_t keywordLine, std::string_view expected, long long found,
                              std::string_view token) {
    const std::string next = token.empty() ? std::string("end of file")
                                           : fmt::format("{} on line {}", quoteToken(token), in.line());
    throw ParseError(in.source(), keywordLine, expected, fmt::format("{}, then {}", found, next));
  }

  Eigen::Vector3d readOffset() {
    const std::size_t keywordLine = in.line();
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      const std::string_view token = in.next();
      if (!parseDouble(token, v[i]) && (token.empty() || in.line() != keywordLine))
        failShort(keywordLine, "3 OFFSET coordinates", i, token);
      v[i] = parseFinite(token, "an OFFSET coordinate", in.source(), in.line());
    }
    return v;
  }

  void readChannels(Joint& joint) {
    const long long count = in.integer("a channel count", 6);
    const std::size_t keywordLine = in.line();
    const std::string expected = fmt::format("{} channel names (Xposition ... Zrotation)", count);
    bool rotationAxes[3] = {false, false, false}, positionAxes[3] = {false, false, false};
    for (long long i = 0; i < count; ++i) {
      const std::string_view token = in.next();
      Channel channel{};
      if (!parseChannel(token, channel)) {
        if (token.empty() || in.line() != keywordLine) failShort(keywordLine, expected, i, token);
        in.fail(expected, TextScanner::describe(token));
      }
      bool& used = (channel.kind == Channel::Kind::Rotation ? rotationAxes : positionAxes)[static_cast<int>(channel.axis)];
      if (used) in.fail("each channel once", fmt::format("{} twice", quoteToken(token)));
      used = true;
      joint.channels.push_back(channel);
    }
  }

  void parse() {
    in.expect("HIERARCHY");
    in.expect("ROOT");
    openJoint(-1);
    // An explicit stack instead of recursion: a hostile file nesting a million braces
    // must give an error, not a stack overflow.
    std::vector<int> open{0};
    std::vector<bool> hasOffset{false}, hasChannels{false};
    while (!open.empty()) {
      const std::string_view token = in.next();
      const std::size_t current = static_cast<std::size_t>(open.back());
      if (token == "OFFSET") {
        if (hasOffset[current]) in.fail("one OFFSET per joint", "a second OFFSET");
        hasOffset[current] = true;
        joints[current].offset = readOffset();
      } else if (token == "CHANNELS") {
        if (hasChannels[current]) in.fail("one CHANNELS line per joint", "a second CHANNELS");
        hasChannels[current] = true;
        readChannels(joints[current]);
      } else if (token == "JOINT") {
        openJoint(static_cast<int>(current));
        open.push_back(static_cast<int>(joints.size() - 1));
        hasOffset.push_back(false);
        hasChannels.push_back(false);
      } else if (token == "End") {
        in.expect("Site");
        if (joints[current].endSite) in.fail("one End Site per joint", "a second End Site");
        in.expect("{");
        in.expect("OFFSET");
        joints[current].endSite = readOffset();
        in.expect("}");
      } else if (token == "}") {
        open.pop_back();
      } else {
        in.fail("OFFSET, CHANNELS, JOINT, End Site or '}'", TextScanner::describe(token));
      }
    }
  }
};

// Splits a data line into numbers; returns how many tokens it holds (possibly more than
// `out` can take, so the message can say how many were found).
std::size_t parseDataLine(std::string_view line, std::span<double> out, std::string_view source, std::size_t lineNo) {
  std::size_t count = 0;
  const char* p = line.data();
  const char* end = p + line.size();
  while (true) {
    while (p < end && (*p == ' ' || *p == '\t' || *p == '\f' || *p == '\v')) ++p;
    if (p >= end) break;
    const char* start = p;
    while (p < end && *p != ' ' && *p != '\t' && *p != '\f' && *p != '\v') ++p;
    if (count < out.size()) {
      const std::string_view token(start, static_cast<std::size_t>(p - start));
      double value = 0;
      const auto [stop, ec] = std::from_chars(start, p, value);
      if (ec != std::errc() || stop != p || !std::isfinite(value)) value = parseFinite(token, "a number", source, lineNo);
      out[count] = value;
    }
    ++count;
  }
  return count;
}

// Files round the frame time (CMU: 0.00833333 for 1/120 s). Snap a rate within 1e-5 of a
// multiple of 0.001 fps back to it, so 120 -> 30 fps resampling lands on exact frames.
double snapFrameTime(double frameTime) {
  const double fps = 1.0 / frameTime;
  const double snapped = std::round(fps * 1000.0) / 1000.0;
  return snapped > 0 && std::abs(fps - snapped) <= 1e-5 * snapped ? 1.0 / snapped : frameTime;
}

}  // namespace

Motion parseBvh(std::string_view text, std::string_view source, const WarningSink& warn) {
  TextScanner in(text, source);
  HierarchyParser hierarchy{in, {}, {}};
  hierarchy.parse();
  auto skeleton = std::make_shared<const Skeleton>(std::move(hierarchy.joints));
  const std::size_t channels = skeleton->channelCount();
  if (channels == 0) in.fail("at least one channel in the hierarchy", "none");

  in.expect("MOTION");
  in.expect("Frames:");
  const long long declared = in.integer("a frame count", kMaxBvhFrames);
  in.expect("Frame");
  in.expect("Time:");
  double frameTime = in.number("a frame time");
  if (!(frameTime > 0)) in.fail("a positive frame time", fmt::format("{}", frameTime));
  // Capture runs at 1 fps or faster; a larger frame time is a broken file, and resampling
  // it would make duration x fps frames (100000 s per frame asked for gigabytes).
  if (frameTime > kMaxBvhFrameTime_s)
    in.fail(fmt::format("a frame time of at most {} s (1 fps)", kMaxBvhFrameTime_s), fmt::format("{}", frameTime));
  frameTime = snapFrameTime(frameTime);
  const std::string_view tail = trim(in.nextLine());
  if (!tail.empty()) in.fail("the end of the Frame Time line", quoteToken(tail));

  // Reserve for the frames declared, but never more than the rest of the text can hold (a
  // value takes at least two bytes): a corrupt Frames: must not allocate gigabytes.
  const std::size_t fit = (text.size() - in.offset()) / (2 * channels) + 1;
  std::vector<double> values;
  values.reserve(std::min(static_cast<std::size_t>(declared), fit) * channels);
  std::size_t frames = 0;
  while (in.offset() < text.size()) {
    const std::string_view line = in.nextLine();
    if (trim(line).empty()) continue;
    values.resize((frames + 1) * channels);
    const std::size_t found = parseDataLine(line, std::span(values).subspan(frames * channels), source, in.line());
    if (found != channels) in.fail(fmt::format("{} channel values", channels), fmt::format("{}", found));
    ++frames;
  }
  if (frames == 0) in.fail("at least one frame of channel values", "end of file");
  if (static_cast<long long>(frames) != declared && warn)
    warn(fmt::format("{}: Frames: says {} but {} frame lines follow; using {}", source, declared, frames, frames));

  const std::size_t joints = skeleton->jointCount();
  std::vector<Eigen::Quaterniond> rotations(frames * joints);
  std::vector<Eigen::Vector3d> translations(frames * skeleton->translatedJoints().size());
  for (std::size_t f = 0; f < frames; ++f) {
    const double* v = values.data() + f * channels;
    for (std::size_t j = 0; j < joints; ++j) {
      const Joint& joint = skeleton->joint(j);
      Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
      Eigen::Vector3d t = joint.offset;
      for (const Channel& c : joint.channels) {
        if (c.kind == Channel::Kind::Rotation)
          q = q * axisRotation(c.axis, *v * kDegToRad);
        else
          t[static_cast<int>(c.axis)] = *v;
        ++v;
      }
      rotations[f * joints + j] = q;
      if (const int slot = skeleton->translationSlot(j); slot >= 0)
        translations[f * skeleton->translatedJoints().size() + static_cast<std::size_t>(slot)] = t;
    }
  }
  return Motion(std::move(skeleton), frameTime, std::move(rotations), std::move(translations));
}

Motion readBvh(std::istream& in, std::string_view source, const WarningSink& warn) {
  const std::string text = readAll(in);
  return parseBvh(text, source, warn);
}

namespace {

// The three rotation axes a joint is written with: its own, completed to three.
std::array<Axis, 3> writtenAxes(const Joint& joint) {
  std::vector<Axis> axes;
  for (const Channel& c : joint.channels)
    if (c.kind == Channel::Kind::Rotation) axes.push_back(c.axis);
  for (Axis a : {Axis::Z, Axis::Y, Axis::X})
    if (std::find(axes.begin(), axes.end(), a) == axes.end() && axes.size() < 3 && !axes.empty()) axes.push_back(a);
  if (axes.empty()) return {Axis::Z, Axis::Y, Axis::X};
  return {axes[0], axes[1], axes[2]};
}

bool hasRotation(const Joint& joint) {
  return std::any_of(joint.channels.begin(), joint.channels.end(),
                     [](const Channel& c) { return c.kind == Channel::Kind::Rotation; });
}

}  // namespace

void writeBvh(std::ostream& out, const Motion& motion, const BvhWriteOptions& options) {
  const Skeleton& skeleton = motion.skeleton();
  const std::size_t n = skeleton.jointCount();
  const double scale = options.lengthScale;
  std::vector<std::vector<int>> children(n);
  for (std::size_t j = 1; j < n; ++j) children[static_cast<std::size_t>(skeleton.joint(j).parent)].push_back(static_cast<int>(j));

  // Per joint, the channels as written: position channels as declared, then rotations
  // (a joint with any rotation channel gets three; a joint with none gets none).
  std::vector<std::vector<Channel>> layout(n);
  std::vector<std::array<Axis, 3>> axes(n);
  std::vector<bool> rotates(n), translates(n);
  for (std::size_t j = 0; j < n; ++j) {
    const Joint& joint = skeleton.joint(j);
    axes[j] = writtenAxes(joint);
    rotates[j] = hasRotation(joint);
    translates[j] = hasPositionChannel(joint);
    for (const Channel& c : joint.channels)
      if (c.kind == Channel::Kind::Position) layout[j].push_back(c);
    if (rotates[j])
      for (Axis a : axes[j]) layout[j].push_back({Channel::Kind::Rotation, a});
  }

  fmt::memory_buffer buffer;
  auto indent = [&](int depth) { buffer.append(std::string(static_cast<std::size_t>(depth), '\t')); };
  auto writeJoint = [&](auto&& self, int j, int depth) -> void {
    const Joint& joint = skeleton.joint(static_cast<std::size_t>(j));
    indent(depth);
    fmt::format_to(std::back_inserter(buffer), "{} {}\n", depth == 0 ? "ROOT" : "JOINT", joint.name);
    indent(depth);
    buffer.append(std::string_view("{\n"));
    indent(depth + 1);
    fmt::format_to(std::back_inserter(buffer), "OFFSET {:.7f} {:.7f} {:.7f}\n", joint.offset.x() * scale,
                   joint.offset.y() * scale, joint.offset.z() * scale);
    indent(depth + 1);
    fmt::format_to(std::back_inserter(buffer), "CHANNELS {}", layout[static_cast<std::size_t>(j)].size());
    for (const Channel& c : layout[static_cast<std::size_t>(j)]) fmt::format_to(std::back_inserter(buffer), " {}", channelName(c));
    buffer.push_back('\n');
    for (int c : children[static_cast<std::size_t>(j)]) self(self, c, depth + 1);
    if (joint.endSite) {
      indent(depth + 1);
      buffer.append(std::string_view("End Site\n"));
      indent(depth + 1);
      buffer.append(std::string_view("{\n"));
      indent(depth + 2);
      fmt::format_to(std::back_inserter(buffer), "OFFSET {:.7f} {:.7f} {:.7f}\n", joint.endSite->x() * scale,
                     joint.endSite->y() * scale, joint.endSite->z() * scale);
      indent(depth + 1);
      buffer.append(std::string_view("}\n"));
    }
    indent(depth);
    buffer.append(std::string_view("}\n"));
  };
  buffer.append(std::string_view("HIERARCHY\n"));
  writeJoint(writeJoint, 0, 0);
  fmt::format_to(std::back_inserter(buffer), "MOTION\nFrames: {}\nFrame Time: {:.10g}\n", motion.frameCount(),
                 motion.frameTime());

  std::vector<std::array<double, 3>> previous(n, {0, 0, 0});
  for (std::size_t f = 0; f < motion.frameCount(); ++f) {
    bool first = true;
    for (std::size_t j = 0; j < n; ++j) {
      if (layout[j].empty()) continue;
      const Eigen::Vector3d t = translates[j] ? Eigen::Vector3d(motion.localTranslation(f, j) * scale) : Eigen::Vector3d::Zero();
      std::array<double, 3> angles{};
      if (rotates[j]) {
        angles = options.continuousAngles ? decomposeEuler(motion.rotation(f, j), axes[j], previous[j])
                                          : principalEuler(motion.rotation(f, j), axes[j]);
        previous[j] = angles;
      }
      int rotationIndex = 0;
      for (const Channel& c : layout[j]) {
        const double value = c.kind == Channel::Kind::Position ? t[static_cast<int>(c.axis)]
                                                               : angles[static_cast<std::size_t>(rotationIndex++)] * kRadToDeg;
        if (!first) buffer.push_back(' ');
        first = false;
        fmt::format_to(std::back_inserter(buffer), "{:.7f}", value);
      }
    }
    buffer.push_back('\n');
    // Flush in chunks so a long clip does not hold the whole text twice.
    if (buffer.size() > (1u << 20)) {
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      buffer.clear();
    }
  }
  out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
}

}  // namespace mgrl
