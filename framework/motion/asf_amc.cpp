#include "mgrl/motion/asf_amc.hpp"

#include <algorithm>
#include <charconv>
#include <istream>
#include <map>
#include <unordered_map>

#include <fmt/format.h>

#include "mgrl/motion/bvh.hpp"
#include "mgrl/core/text_scanner.hpp"

namespace mgrl {
namespace {

std::string lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

std::vector<std::string_view> splitBlanks(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

// Axis order strings such as "XYZ": each letter once.
std::vector<Axis> parseAxisOrder(TextScanner& in, std::string_view token) {
  std::vector<Axis> axes;
  const std::string order = lower(token);
  for (char c : order) {
    if (c < 'x' || c > 'z') in.fail("an axis order such as XYZ", quoteToken(token));
    const Axis a = static_cast<Axis>(c - 'x');
    if (std::find(axes.begin(), axes.end(), a) != axes.end()) in.fail("an axis order such as XYZ", quoteToken(token));
    axes.push_back(a);
  }
  if (axes.size() != 3) in.fail("an axis order such as XYZ", quoteToken(token));
  return axes;
}

// Rotation applying axes[0] first: R = R(axes[2]) R(axes[1]) R(axes[0]); `angles` indexed by axis.
Eigen::Quaterniond appliedInOrder(const std::vector<Axis>& axes, const Eigen::Vector3d& angles) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (Axis a : axes) q = axisRotation(a, angles[static_cast<int>(a)]) * q;
  return q;
}

struct RawBone {
  std::string name;
  std::size_t line = 0;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double length = 0;
  Eigen::Vector3d axisAngles = Eigen::Vector3d::Zero();
  std::vector<Axis> axisOrder{Axis::X, Axis::Y, Axis::Z};
  std::vector<int> dofs;
};

bool startsSection(std::string_view token) { return !token.empty() && token.front() == ':'; }

int parseDof(std::string_view token) {
  static const std::map<std::string, int, std::less<>> kDofs = {{"rx", 0}, {"ry", 1}, {"rz", 2},
                                                                {"tx", 3}, {"ty", 4}, {"tz", 5}};
  const auto it = kDofs.find(lower(token));
  return it == kDofs.end() ? -1 : it->second;
}

}  // namespace

AsfSkeleton parseAsf(std::string_view text, std::string_view source) {
  TextScanner in(text, source);
  AsfSkeleton result;
  std::vector<Axis> rootOrderApplied;  // rotation axes in the order the root applies them
  std::vector<int> rootDofs;
  Eigen::Vector3d rootPosition = Eigen::Vector3d::Zero(), rootOrientation = Eigen::Vector3d::Zero();
  std::vector<Axis> rootAxis{Axis::X, Axis::Y, Axis::Z};
  std::vector<RawBone> bones;
  std::unordered_map<std::string, std::size_t> boneIndex;
  std::vector<std::vector<std::size_t>> children;  // index bones.size() is the root
  std::vector<long> parentOf;
  std::vector<std::size_t> parentLine;
  bool sawRoot = false, sawBones = false, sawHierarchy = false;
  double angleScale = kDegToRad;

  std::string_view token = in.next();
  while (!token.empty()) {
    if (token.front() == '#') {
      in.nextLine();
      token = in.next();
      continue;
    }
    if (token == ":version" || token == ":name") {
      in.nextLine();
      token = in.next();
    } else if (token == ":documentation") {
      // Free text up to the next section keyword.
      do token = in.next();
      while (!token.empty() && !startsSection(token));
    } else if (token == ":units") {
      for (token = in.next(); !token.empty() && !startsSection(token); token = in.next()) {
        if (token == "mass") {
          in.number("a mass unit");
        } else if (token == "length") {
          result.lengthPerInch = in.number("a length unit");
          // CMU writes 0.45; a unit far outside [0.001, 1000] makes skeletons of nanometres or
          // of millions of metres (issue 19), never a person.
          if (!(result.lengthPerInch >= 1e-3 && result.lengthPerInch <= 1e3))
            in.fail("a length unit in [0.001, 1000] (CMU: 0.45)", fmt::format("{}", result.lengthPerInch));
        } else if (token == "angle") {
          const std::string_view unit = in.require("deg or rad");
          if (unit == "deg") angleScale = kDegToRad;
          else if (unit == "rad") angleScale = 1.0;
          else in.fail("deg or rad", quoteToken(unit));
        } else {
          in.fail("mass, length or angle", quoteToken(token));
        }
      }
    } else if (token == ":root") {
      sawRoot = true;
      for (token = in.next(); !token.empty() && !startsSection(token); token = in.next()) {
        if (token == "order") {
          in.skipBlanks();
          for (std::string_view dof : splitBlanks(in.nextLine())) {
            const int d = parseDof(dof);
            if (d < 0 || std::find(rootDofs.begin(), rootDofs.end(), d) != rootDofs.end())
              in.fail("root order channels TX TY TZ RX RY RZ, each once", quoteToken(dof));
            rootDofs.push_back(d);
            if (d < 3) rootOrderApplied.push_back(static_cast<Axis>(d));
          }
        } else if (token == "axis") {
          rootAxis = parseAxisOrder(in, in.require("an axis order"));
        } else if (token == "position") {
          for (int i = 0; i < 3; ++i) rootPosition[i] = in.number("a root position coordinate");
        } else if (token == "orientation") {
          for (int i = 0; i < 3; ++i) rootOrientation[i] = in.number("a root orientation angle");
        } else {
          in.fail("order, axis, position or orientation", quoteToken(token));
        }
      }
    } else if (token == ":bonedata") {
      // :hierarchy sized its tables by the bones before it.
      if (sawHierarchy) in.fail(":bonedata before :hierarchy", "':bonedata' after it");
      sawBones = true;
      for (token = in.next(); token == "begin"; token = in.next()) {
        RawBone bone;
        bone.line = in.line();
        bool sawName = false;
        for (token = in.next(); token != "end"; token = in.next()) {
          if (token.empty()) in.fail("'end' of the bone", "end of file");
          if (token == "id") {
            in.require("a bone id");
          } else if (token == "name") {
            bone.name = std::string(in.require("a bone name"));
            bone.line = in.line();
            sawName = true;
          } else if (token == "direction") {
            for (int i = 0; i < 3; ++i) bone.direction[i] = in.number("a direction coordinate");
          } else if (token == "length") {
            bone.length = in.number("a bone length");
            if (bone.length < 0) in.fail("a non-negative bone length", fmt::format("{}", bone.length));
          } else if (token == "axis") {
            for (int i = 0; i < 3; ++i) bone.axisAngles[i] = in.number("an axis angle");
            bone.axisOrder = parseAxisOrder(in, in.require("an axis order"));
          } else if (token == "dof") {
            in.skipBlanks();
            for (std::string_view dof : splitBlanks(in.nextLine())) {
              const int d = parseDof(dof);
              if (d < 0 || d > 2 || std::find(bone.dofs.begin(), bone.dofs.end(), d) != bone.dofs.end())
                in.fail("rotational degrees of freedom rx, ry, rz, each once", quoteToken(dof));
              bone.dofs.push_back(d);
            }
          } else if (token == "limits") {
            // One "(min max)" pair per degree of freedom; mgrl does not enforce them.
            for (std::size_t k = 0; k < bone.dofs.size(); ++k) {
              std::string_view t;
              do {
                t = in.require("a limits pair such as (-10.0 170.0)");
                if (startsSection(t) || t == "end") in.fail("a limits pair such as (-10.0 170.0)", quoteToken(t));
              } while (t.back() != ')');
            }
          } else if (token == "bodymass" || token == "cofmass") {
            in.number("a mass value");
          } else {
            in.fail("id, name, direction, length, axis, dof, limits or end", TextScanner::describe(token));
          }
        }
        if (!sawName) in.fail("a bone name before 'end'", "none");
        if (bone.name == "root") throw ParseError(source, bone.line, "a bone name other than root", "'root'");
        if (bone.direction.norm() > 0) bone.direction.normalize();
        if (auto [it, fresh] = boneIndex.emplace(bone.name, bones.size()); !fresh)
          throw ParseError(source, bone.line, "a unique bone name", fmt::format("'{}' again", bone.name));
        bones.push_back(std::move(bone));
      }
    } else if (token == ":hierarchy") {
      if (sawHierarchy) in.fail("one :hierarchy section", "a second ':hierarchy'");
      sawHierarchy = true;
      children.assign(bones.size() + 1, {});
      parentOf.assign(bones.size(), -2);
      parentLine.assign(bones.size(), 0);
      in.expect("begin");
      in.nextLine();
      while (true) {
        if (in.offset() >= text.size()) in.fail("'end' of the hierarchy", "end of file");
        const auto names = splitBlanks(in.nextLine());
        if (names.empty()) continue;
        if (names[0] == "end") break;
        auto lookup = [&](std::string_view name) -> long {
          if (name == "root") return static_cast<long>(bones.size());
          const auto it = boneIndex.find(std::string(name));
          if (it == boneIndex.end()) in.fail("a bone defined in :bonedata", quoteToken(name));
          return static_cast<long>(it->second);
        };
        const long parent = lookup(names[0]);
        if (names.size() < 2) in.fail("a parent followed by its children", "a line with one name");
        for (std::size_t k = 1; k < names.size(); ++k) {
          const long child = lookup(names[k]);
          if (child == static_cast<long>(bones.size()))
            in.fail("a tree rooted at root", fmt::format("a cycle: root listed as a child of {}", quoteToken(names[0])));
          if (parentOf[static_cast<std::size_t>(child)] != -2)
            in.fail("one parent per bone", fmt::format("{} given a second parent {}", quoteToken(names[k]), quoteToken(names[0])));
          parentOf[static_cast<std::size_t>(child)] = parent;
          parentLine[static_cast<std::size_t>(child)] = in.line();
          children[static_cast<std::size_t>(parent)].push_back(static_cast<std::size_t>(child));
        }
      }
      token = in.next();
    } else {
      in.fail(":version, :name, :units, :documentation, :root, :bonedata or :hierarchy", quoteToken(token));
    }
  }
  if (!sawRoot) in.fail("a :root section", "end of file");
  if (!sawBones) in.fail("a :bonedata section", "end of file");
  if (!sawHierarchy) in.fail("a :hierarchy section", "end of file");
  if (rootOrderApplied.empty()) rootOrderApplied = {Axis::X, Axis::Y, Axis::Z};

  // Depth-first from the root gives parent-before-child order. Bones it never reaches
  // hang off a cycle or off nothing.
  std::vector<std::size_t> order;
  std::vector<int> jointOf(bones.size(), -1);
  {
    std::vector<std::size_t> stack(children[bones.size()].rbegin(), children[bones.size()].rend());
    while (!stack.empty()) {
      const std::size_t b = stack.back();
      stack.pop_back();
      jointOf[b] = static_cast<int>(order.size() + 1);
      order.push_back(b);
      stack.insert(stack.end(), children[b].rbegin(), children[b].rend());
    }
  }
  for (std::size_t b = 0; b < bones.size(); ++b) {
    if (jointOf[b] >= 0) continue;
    if (parentOf[b] == -2)
      throw ParseError(source, bones[b].line, "every bone in :hierarchy", fmt::format("'{}' missing from it", bones[b].name));
    // Walk up the parents: if we come back to a bone, it is a cycle.
    std::vector<bool> seen(bones.size(), false);
    std::size_t walk = b;
    while (parentOf[walk] >= 0 && parentOf[walk] < static_cast<long>(bones.size()) && !seen[walk]) {
      seen[walk] = true;
      walk = static_cast<std::size_t>(parentOf[walk]);
    }
    throw ParseError(source, parentLine[walk], "a tree rooted at root",
                     fmt::format("a cycle through '{}'", bones[walk].name));
  }

  // Root joint: BVH-style position then rotation channels (composition order = reverse
  // of application order).
  std::vector<Joint> joints;
  Joint root;
  root.name = "root";
  root.offset = rootPosition;
  for (Axis a : {Axis::X, Axis::Y, Axis::Z}) root.channels.push_back({Channel::Kind::Position, a});
  result.rootRotationOrder.assign(rootOrderApplied.rbegin(), rootOrderApplied.rend());
  for (Axis a : result.rootRotationOrder) root.channels.push_back({Channel::Kind::Rotation, a});
  joints.push_back(root);
  AsfSkeleton::Bone rootBone;
  rootBone.name = "root";
  rootBone.dofs = rootDofs;
  rootBone.axis = appliedInOrder(rootAxis, rootOrientation * angleScale);
  rootBone.axisInverse = rootBone.axis.conjugate();
  result.bones.push_back(rootBone);

  for (std::size_t b : order) {
    const RawBone& bone = bones[b];
    Joint joint;
    joint.name = bone.name;
    const long parent = parentOf[b];
    const bool parentIsRoot = parent == static_cast<long>(bones.size());
    joint.parent = parentIsRoot ? 0 : jointOf[static_cast<std::size_t>(parent)];
    joint.offset = parentIsRoot ? Eigen::Vector3d::Zero()
                                : Eigen::Vector3d(bones[static_cast<std::size_t>(parent)].direction *
                                                  bones[static_cast<std::size_t>(parent)].length);
    if (children[b].empty()) joint.endSite = bone.direction * bone.length;
    if (!bone.dofs.empty())
      for (Axis a : {Axis::Z, Axis::Y, Axis::X}) joint.channels.push_back({Channel::Kind::Rotation, a});
    joints.push_back(std::move(joint));
    AsfSkeleton::Bone info;
    info.name = bone.name;
    info.dofs = bone.dofs;
    info.axis = appliedInOrder(bone.axisOrder, bone.axisAngles * angleScale);
    info.axisInverse = info.axis.conjugate();
    result.bones.push_back(std::move(info));
  }
  result.degrees = angleScale != 1.0;
  result.skeleton = std::make_shared<const Skeleton>(std::move(joints));
  return result;
}

AsfSkeleton readAsf(std::istream& in, std::string_view source) {
  const std::string text = readAll(in);
  return parseAsf(text, source);
}

Motion parseAmc(std::string_view text, std::string_view source, const AsfSkeleton& asf, double frameTime) {
  if (!(frameTime > 0)) throw ParseError(source, 0, "a positive frame time", fmt::format("{}", frameTime));
  TextScanner in(text, source);
  const Skeleton& skeleton = *asf.skeleton;
  const std::size_t joints = skeleton.jointCount();
  std::unordered_map<std::string_view, std::size_t> jointOf;
  for (std::size_t j = 0; j < joints; ++j) jointOf.emplace(asf.bones[j].name, j);
  double angleScale = asf.degrees ? kDegToRad : 1.0;

  std::vector<Eigen::Quaterniond> rotations;
  std::vector<Eigen::Vector3d> translations;
  // seenInFrame[j] == frames: bone j has its values in the current (1-based) frame.
  std::vector<std::size_t> seenInFrame(joints, 0);
  std::size_t frames = 0;
  long long lastNumber = -1;

  auto checkComplete = [&](std::string_view found) {
    for (std::size_t j = 0; j < joints; ++j)
      if (!asf.bones[j].dofs.empty() && seenInFrame[j] != frames)
        in.fail(fmt::format("values for bone '{}' in frame {}", asf.bones[j].name, lastNumber), found);
  };

  while (in.offset() < text.size()) {
    const std::string_view line = in.nextLine();
    const auto tokens = splitBlanks(line);
    if (tokens.empty() || tokens[0].front() == '#') continue;
    if (frames == 0 && tokens[0].front() == ':') {
      if (tokens[0] == ":DEGREES") angleScale = kDegToRad;
      else if (tokens[0] == ":RADIANS") angleScale = 1.0;
      else if (tokens[0] != ":FULLY-SPECIFIED")
        in.fail(":FULLY-SPECIFIED, :DEGREES, :RADIANS or a frame number", quoteToken(tokens[0]));
      continue;
    }
    long long number = 0;
    const auto [end, ec] = std::from_chars(tokens[0].data(), tokens[0].data() + tokens[0].size(), number);
    if (tokens.size() == 1 && ec == std::errc() && end == tokens[0].data() + tokens[0].size()) {
      if (frames > 0) checkComplete(fmt::format("frame {} starting", number));
      if (number <= lastNumber) in.fail(fmt::format("a frame number after {}", lastNumber), quoteToken(tokens[0]));
      if (frames >= static_cast<std::size_t>(kMaxBvhFrames)) in.fail(fmt::format("at most {} frames", kMaxBvhFrames), "more");
      lastNumber = number;
      ++frames;
      // The frame starts at the rest pose; bones without degrees of freedom stay there.
      rotations.resize(frames * joints, Eigen::Quaterniond::Identity());
      translations.resize(frames, skeleton.joint(0).offset);
      continue;
    }
    if (frames == 0) in.fail("a frame number", quoteToken(tokens[0]));
    const auto it = jointOf.find(tokens[0]);
    if (it == jointOf.end()) in.fail("a bone of the skeleton", quoteToken(tokens[0]));
    const std::size_t j = it->second;
    const AsfSkeleton::Bone& bone = asf.bones[j];
    if (seenInFrame[j] == frames) in.fail(fmt::format("bone '{}' once per frame", bone.name), "it again");
    seenInFrame[j] = frames;
    if (tokens.size() - 1 != bone.dofs.size())
      in.fail(fmt::format("{} value{} for bone '{}'", bone.dofs.size(), bone.dofs.size() == 1 ? "" : "s", bone.name),
              fmt::format("{}", tokens.size() - 1));
    Eigen::Vector3d shift = Eigen::Vector3d::Zero();
    // Degrees of freedom apply in the order listed: M = R(last) ... R(first).
    Eigen::Quaterniond m = Eigen::Quaterniond::Identity();
    for (std::size_t k = 0; k < bone.dofs.size(); ++k) {
      const double v = parseFinite(tokens[k + 1], "a number", source, in.line());
      const int d = bone.dofs[k];
      if (d < 3)
        m = axisRotation(static_cast<Axis>(d), v * angleScale) * m;
      else
        shift[d - 3] = v;
    }
    const std::size_t f = frames - 1;
    if (j == 0) {
      rotations[f * joints] = bone.axis * m;
      translations[f] = skeleton.joint(0).offset + shift;
    } else {
      rotations[f * joints + j] = bone.axis * m * bone.axisInverse;
    }
  }
  if (frames == 0) in.fail("at least one frame", "end of file");
  checkComplete("end of file");
  return Motion(asf.skeleton, frameTime, std::move(rotations), std::move(translations));
}

Motion readAmc(std::istream& in, std::string_view source, const AsfSkeleton& asf, double frameTime) {
  const std::string text = readAll(in);
  return parseAmc(text, source, asf, frameTime);
}

}  // namespace mgrl
