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

namespace {

// parseAsf's state across the file's sections: one method per section, each starting at
// its keyword's next token and returning the token that ends it (the next section's).
class AsfReader {
 public:
  AsfReader(std::string_view text, std::string_view source) : in_(text, source), text_(text), source_(source) {}

  AsfSkeleton read() {
    std::string_view token = in_.next();
    while (!token.empty()) {
      if (token.front() == '#') {
        in_.nextLine();
        token = in_.next();
        continue;
      }
      if (token == ":version" || token == ":name") {
        in_.nextLine();
        token = in_.next();
      } else if (token == ":documentation") {
        // Free text up to the next section keyword.
        do token = in_.next();
        while (!token.empty() && !startsSection(token));
      } else if (token == ":units") {
        token = units();
      } else if (token == ":root") {
        token = root();
      } else if (token == ":bonedata") {
        token = bonedata();
      } else if (token == ":hierarchy") {
        hierarchy();
        token = in_.next();
      } else {
        in_.fail(":version, :name, :units, :documentation, :root, :bonedata or :hierarchy", quoteToken(token));
      }
    }
    if (!sawRoot_) in_.fail("a :root section", "end of file");
    if (!sawBones_) in_.fail("a :bonedata section", "end of file");
    if (!sawHierarchy_) in_.fail("a :hierarchy section", "end of file");
    if (rootOrderApplied_.empty()) rootOrderApplied_ = {Axis::X, Axis::Y, Axis::Z};
    std::vector<int> jointOf;
    const std::vector<std::size_t> order = depthFirstOrder(jointOf);
    return build(order, jointOf);
  }

 private:
  std::string_view units() {
    std::string_view token;
    for (token = in_.next(); !token.empty() && !startsSection(token); token = in_.next()) {
      if (token == "mass") {
        in_.number("a mass unit");
      } else if (token == "length") {
        result_.lengthPerInch = in_.number("a length unit");
        // CMU writes 0.45; a unit far outside [0.001, 1000] makes skeletons of nanometres or
        // of millions of metres, never a person.
        if (!(result_.lengthPerInch >= 1e-3 && result_.lengthPerInch <= 1e3))
          in_.fail("a length unit in [0.001, 1000] (CMU: 0.45)", fmt::format("{}", result_.lengthPerInch));
      } else if (token == "angle") {
        const std::string_view unit = in_.require("deg or rad");
        if (unit == "deg")
          angleScale_ = kDegToRad;
        else if (unit == "rad")
          angleScale_ = 1.0;
        else
          in_.fail("deg or rad", quoteToken(unit));
      } else {
        in_.fail("mass, length or angle", quoteToken(token));
      }
    }
    return token;
  }

  std::string_view root() {
    sawRoot_ = true;
    std::string_view token;
    for (token = in_.next(); !token.empty() && !startsSection(token); token = in_.next()) {
      if (token == "order") {
        in_.skipBlanks();
        for (std::string_view dof : splitBlanks(in_.nextLine())) {
          const int d = parseDof(dof);
          if (d < 0 || std::find(rootDofs_.begin(), rootDofs_.end(), d) != rootDofs_.end())
            in_.fail("root order channels TX TY TZ RX RY RZ, each once", quoteToken(dof));
          rootDofs_.push_back(d);
          if (d < 3) rootOrderApplied_.push_back(static_cast<Axis>(d));
        }
      } else if (token == "axis") {
        rootAxis_ = parseAxisOrder(in_, in_.require("an axis order"));
      } else if (token == "position") {
        for (int i = 0; i < 3; ++i) rootPosition_[i] = in_.number("a root position coordinate");
      } else if (token == "orientation") {
        for (int i = 0; i < 3; ++i) rootOrientation_[i] = in_.number("a root orientation angle");
      } else {
        in_.fail("order, axis, position or orientation", quoteToken(token));
      }
    }
    return token;
  }

  std::string_view bonedata() {
    // :hierarchy sized its tables by the bones before it.
    if (sawHierarchy_) in_.fail(":bonedata before :hierarchy", "':bonedata' after it");
    sawBones_ = true;
    std::string_view token;
    for (token = in_.next(); token == "begin"; token = in_.next()) {
      RawBone bone = this->bone();
      if (bone.name == "root") throw ParseError(source_, bone.line, "a bone name other than root", "'root'");
      if (bone.direction.norm() > 0) bone.direction.normalize();
      if (auto [it, fresh] = boneIndex_.emplace(bone.name, bones_.size()); !fresh)
        throw ParseError(source_, bone.line, "a unique bone name", fmt::format("'{}' again", bone.name));
      bones_.push_back(std::move(bone));
    }
    return token;
  }

  // One bone's "begin ... end" block, "begin" read.
  RawBone bone() {
    RawBone bone;
    bone.line = in_.line();
    bool sawName = false;
    for (std::string_view token = in_.next(); token != "end"; token = in_.next()) {
      if (token.empty()) in_.fail("'end' of the bone", "end of file");
      if (token == "id") {
        in_.require("a bone id");
      } else if (token == "name") {
        bone.name = std::string(in_.require("a bone name"));
        bone.line = in_.line();
        sawName = true;
      } else if (token == "direction") {
        for (int i = 0; i < 3; ++i) bone.direction[i] = in_.number("a direction coordinate");
      } else if (token == "length") {
        bone.length = in_.number("a bone length");
        if (bone.length < 0) in_.fail("a non-negative bone length", fmt::format("{}", bone.length));
      } else if (token == "axis") {
        for (int i = 0; i < 3; ++i) bone.axisAngles[i] = in_.number("an axis angle");
        bone.axisOrder = parseAxisOrder(in_, in_.require("an axis order"));
      } else if (token == "dof") {
        in_.skipBlanks();
        for (std::string_view dof : splitBlanks(in_.nextLine())) {
          const int d = parseDof(dof);
          if (d < 0 || d > 2 || std::find(bone.dofs.begin(), bone.dofs.end(), d) != bone.dofs.end())
            in_.fail("rotational degrees of freedom rx, ry, rz, each once", quoteToken(dof));
          bone.dofs.push_back(d);
        }
      } else if (token == "limits") {
        // One "(min max)" pair per degree of freedom; mgrl does not enforce them.
        for (std::size_t k = 0; k < bone.dofs.size(); ++k) {
          std::string_view t;
          do {
            t = in_.require("a limits pair such as (-10.0 170.0)");
            if (startsSection(t) || t == "end") in_.fail("a limits pair such as (-10.0 170.0)", quoteToken(t));
          } while (t.back() != ')');
        }
      } else if (token == "bodymass" || token == "cofmass") {
        in_.number("a mass value");
      } else {
        in_.fail("id, name, direction, length, axis, dof, limits or end", TextScanner::describe(token));
      }
    }
    if (!sawName) in_.fail("a bone name before 'end'", "none");
    return bone;
  }

  void hierarchy() {
    if (sawHierarchy_) in_.fail("one :hierarchy section", "a second ':hierarchy'");
    sawHierarchy_ = true;
    children_.assign(bones_.size() + 1, {});
    parentOf_.assign(bones_.size(), -2);
    parentLine_.assign(bones_.size(), 0);
    in_.expect("begin");
    in_.nextLine();
    auto lookup = [&](std::string_view name) -> long {
      if (name == "root") return static_cast<long>(bones_.size());
      const auto it = boneIndex_.find(std::string(name));
      if (it == boneIndex_.end()) in_.fail("a bone defined in :bonedata", quoteToken(name));
      return static_cast<long>(it->second);
    };
    while (true) {
      if (in_.offset() >= text_.size()) in_.fail("'end' of the hierarchy", "end of file");
      const auto names = splitBlanks(in_.nextLine());
      if (names.empty()) continue;
      if (names[0] == "end") break;
      const long parent = lookup(names[0]);
      if (names.size() < 2) in_.fail("a parent followed by its children", "a line with one name");
      for (std::size_t k = 1; k < names.size(); ++k) {
        const long child = lookup(names[k]);
        if (child == static_cast<long>(bones_.size()))
          in_.fail("a tree rooted at root", fmt::format("a cycle: root listed as a child of {}", quoteToken(names[0])));
        if (parentOf_[static_cast<std::size_t>(child)] != -2)
          in_.fail("one parent per bone",
                   fmt::format("{} given a second parent {}", quoteToken(names[k]), quoteToken(names[0])));
        parentOf_[static_cast<std::size_t>(child)] = parent;
        parentLine_[static_cast<std::size_t>(child)] = in_.line();
        children_[static_cast<std::size_t>(parent)].push_back(static_cast<std::size_t>(child));
      }
    }
  }

  // Depth-first from the root gives parent-before-child order (jointOf: each bone's joint).
  // Bones it never reaches hang off a cycle or off nothing.
  std::vector<std::size_t> depthFirstOrder(std::vector<int>& jointOf) const {
    std::vector<std::size_t> order;
    jointOf.assign(bones_.size(), -1);
    std::vector<std::size_t> stack(children_[bones_.size()].rbegin(), children_[bones_.size()].rend());
    while (!stack.empty()) {
      const std::size_t b = stack.back();
      stack.pop_back();
      jointOf[b] = static_cast<int>(order.size() + 1);
      order.push_back(b);
      stack.insert(stack.end(), children_[b].rbegin(), children_[b].rend());
    }
    for (std::size_t b = 0; b < bones_.size(); ++b) {
      if (jointOf[b] >= 0) continue;
      if (parentOf_[b] == -2)
        throw ParseError(source_, bones_[b].line, "every bone in :hierarchy",
                         fmt::format("'{}' missing from it", bones_[b].name));
      // Walk up the parents: if we come back to a bone, it is a cycle.
      std::vector<bool> seen(bones_.size(), false);
      std::size_t walk = b;
      while (parentOf_[walk] >= 0 && parentOf_[walk] < static_cast<long>(bones_.size()) && !seen[walk]) {
        seen[walk] = true;
        walk = static_cast<std::size_t>(parentOf_[walk]);
      }
      throw ParseError(source_, parentLine_[walk], "a tree rooted at root",
                       fmt::format("a cycle through '{}'", bones_[walk].name));
    }
    return order;
  }

  AsfSkeleton build(const std::vector<std::size_t>& order, const std::vector<int>& jointOf) {
    AsfSkeleton& result = result_;
    // Root joint: BVH-style position then rotation channels (composition order = reverse
    // of application order).
    std::vector<Joint> joints;
    Joint root;
    root.name = "root";
    root.offset = rootPosition_;
    for (Axis a : {Axis::X, Axis::Y, Axis::Z}) root.channels.push_back({Channel::Kind::Position, a});
    result.rootRotationOrder.assign(rootOrderApplied_.rbegin(), rootOrderApplied_.rend());
    for (Axis a : result.rootRotationOrder) root.channels.push_back({Channel::Kind::Rotation, a});
    joints.push_back(root);
    AsfSkeleton::Bone rootBone;
    rootBone.name = "root";
    rootBone.dofs = rootDofs_;
    rootBone.axis = appliedInOrder(rootAxis_, rootOrientation_ * angleScale_);
    rootBone.axisInverse = rootBone.axis.conjugate();
    result.bones.push_back(rootBone);

    for (std::size_t b : order) {
      const RawBone& bone = bones_[b];
      Joint joint;
      joint.name = bone.name;
      const long parent = parentOf_[b];
      const bool parentIsRoot = parent == static_cast<long>(bones_.size());
      joint.parent = parentIsRoot ? 0 : jointOf[static_cast<std::size_t>(parent)];
      joint.offset = parentIsRoot ? Eigen::Vector3d::Zero()
                                  : Eigen::Vector3d(bones_[static_cast<std::size_t>(parent)].direction *
                                                    bones_[static_cast<std::size_t>(parent)].length);
      if (children_[b].empty()) joint.endSite = bone.direction * bone.length;
      if (!bone.dofs.empty())
        for (Axis a : {Axis::Z, Axis::Y, Axis::X}) joint.channels.push_back({Channel::Kind::Rotation, a});
      joints.push_back(std::move(joint));
      AsfSkeleton::Bone info;
      info.name = bone.name;
      info.dofs = bone.dofs;
      info.axis = appliedInOrder(bone.axisOrder, bone.axisAngles * angleScale_);
      info.axisInverse = info.axis.conjugate();
      result.bones.push_back(std::move(info));
    }
    result.degrees = angleScale_ != 1.0;
    result.skeleton = std::make_shared<const Skeleton>(std::move(joints));
    return std::move(result);
  }

  TextScanner in_;
  std::string_view text_, source_;
  AsfSkeleton result_;
  std::vector<Axis> rootOrderApplied_;  // rotation axes in the order the root applies them
  std::vector<int> rootDofs_;
  Eigen::Vector3d rootPosition_ = Eigen::Vector3d::Zero(), rootOrientation_ = Eigen::Vector3d::Zero();
  std::vector<Axis> rootAxis_{Axis::X, Axis::Y, Axis::Z};
  std::vector<RawBone> bones_;
  std::unordered_map<std::string, std::size_t> boneIndex_;
  std::vector<std::vector<std::size_t>> children_;  // index bones_.size() is the root
  std::vector<long> parentOf_;
  std::vector<std::size_t> parentLine_;
  bool sawRoot_ = false, sawBones_ = false, sawHierarchy_ = false;
  double angleScale_ = kDegToRad;
};

}  // namespace

AsfSkeleton parseAsf(std::string_view text, std::string_view source) { return AsfReader(text, source).read(); }

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
