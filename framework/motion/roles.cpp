#include "mgrl/motion/roles.hpp"

#include <algorithm>
#include <cctype>
#include <optional>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"
#include "mgrl/motion/kinematics.hpp"

namespace mgrl {
namespace {

struct RoleSpec {
  const char* name;  // without side prefix
  bool sided;
  std::vector<std::string_view> bases;  // normalised base names, in priority order
};

// CMU BVH calls the wrist "Hand" and the palm "FingerBase"; CMU ASF calls them "wrist" and
// "hand"; SNU and Mixamo have only "Hand". Priorities below resolve all three.
const std::vector<RoleSpec>& roleSpecs() {
  static const std::vector<RoleSpec> specs = {
      {"fist", true, {"fingerbase", "fist", "hand"}},
      {"wrist", true, {"wrist", "hand"}},
      {"forearm", true, {"forearm", "lowerarm", "radius", "elbow"}},
      {"shoulder", true, {"upperarm", "humerus", "arm", "shoulder"}},
      {"ankle", true, {"foot", "ankle"}},
      {"toe", true, {"toebase", "toe", "toes", "ball"}},
      {"head", false, {"head"}},
      {"pelvis", false, {"hips", "pelvis", "hip", "root"}},
  };
  return specs;
}

// Lowercase letters and digits of the name after any namespace ("mixamorig:LeftHand").
std::string normalise(std::string_view name) {
  const auto cut = name.find_last_of(":|");
  if (cut != std::string_view::npos) name.remove_prefix(cut + 1);
  std::string result;
  for (char c : name)
    if (std::isalnum(static_cast<unsigned char>(c))) result += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return result;
}

std::vector<std::string> candidates(const RoleSpec& spec, std::optional<Side> side) {
  std::vector<std::string> names;
  for (std::string_view base : spec.bases) {
    if (!side) {
      names.emplace_back(base);
      continue;
    }
    const std::string word = *side == Side::Left ? "left" : "right";
    const std::string letter = *side == Side::Left ? "l" : "r";
    names.push_back(word + std::string(base));
    names.push_back(letter + std::string(base));
    names.push_back(std::string(base) + word);
    names.push_back(std::string(base) + letter);
  }
  return names;
}

std::string roleKey(const RoleSpec& spec, std::optional<Side> side) {
  return side ? fmt::format("{}_{}", sideName(*side), spec.name) : std::string(spec.name);
}

// `normalised[j]` is normalise() of joint j's name, computed once per skeleton. -1 if no
// joint has one of the role's names (an override must name a joint).
int matchJoint(const Skeleton& skeleton, const std::vector<std::string>& normalised, const RoleSpec& spec,
               std::optional<Side> side, const RoleOverrides& overrides, std::string_view source) {
  const std::string key = roleKey(spec, side);
  if (auto it = overrides.find(key); it != overrides.end()) {
    const int index = skeleton.find(it->second);
    if (index < 0)
      throw Error(fmt::format("{}: role {}: expected a joint of the skeleton, found '{}'; joints: {}", source, key,
                              it->second, skeleton.jointList()));
    return index;
  }
  for (const std::string& name : candidates(spec, side))
    for (std::size_t j = 0; j < normalised.size(); ++j)
      if (normalised[j] == name) return static_cast<int>(j);
  if (spec.name == std::string_view("pelvis")) return 0;  // the root is the pelvis by convention
  return -1;
}

[[noreturn]] void throwMissingRole(const Skeleton& skeleton, const RoleSpec& spec, std::optional<Side> side,
                                   std::string_view source) {
  const std::string key = roleKey(spec, side);
  const auto names = candidates(spec, side);
  throw Error(fmt::format("{}: expected a joint for role {} (a name like {}), found none; joints: {}; "
                          "set it with --role {}=JOINT",
                          source, key, fmt::join(names.begin(), names.begin() + std::min<std::size_t>(4, names.size()), ", "),
                          skeleton.jointList(), key));
}

int findJoint(const Skeleton& skeleton, const std::vector<std::string>& normalised, const RoleSpec& spec,
              std::optional<Side> side, const RoleOverrides& overrides, std::string_view source) {
  const int index = matchJoint(skeleton, normalised, spec, side, overrides, source);
  if (index < 0) throwMissingRole(skeleton, spec, side, source);
  return index;
}

std::vector<std::vector<int>> childLists(const Skeleton& skeleton) {
  std::vector<std::vector<int>> children(skeleton.jointCount());
  for (std::size_t j = 1; j < skeleton.jointCount(); ++j)
    children[static_cast<std::size_t>(skeleton.joint(j).parent)].push_back(static_cast<int>(j));
  return children;
}

// Rest-pose extent of joints and end sites along `up`.
double extentAlong(const Skeleton& skeleton, const std::vector<Eigen::Vector3d>& rest, const Eigen::Vector3d& up) {
  double lo = 1e300, hi = -1e300;
  for (std::size_t j = 0; j < skeleton.jointCount(); ++j) {
    lo = std::min(lo, rest[j].dot(up));
    hi = std::max(hi, rest[j].dot(up));
    if (const auto& end = skeleton.joint(j).endSite) {
      const double h = (rest[j] + *end).dot(up);  // rest rotations are identity
      lo = std::min(lo, h);
      hi = std::max(hi, h);
    }
  }
  return hi - lo;
}

}  // namespace

std::vector<std::string> roleNames() {
  std::vector<std::string> names;
  for (const RoleSpec& spec : roleSpecs()) {
    if (spec.sided) {
      names.push_back(roleKey(spec, Side::Left));
      names.push_back(roleKey(spec, Side::Right));
    } else {
      names.push_back(roleKey(spec, std::nullopt));
    }
  }
  return names;
}

std::vector<int> roleJointIndices(const SkeletonRoles& roles) {
  // The order of roleSpecs(): fist, wrist, forearm, shoulder, ankle, toe, head, pelvis.
  std::vector<int> joints;
  for (const std::array<int, 2>* sided : {&roles.fist, &roles.wrist, &roles.forearm, &roles.shoulder, &roles.ankle, &roles.toe})
    joints.insert(joints.end(), sided->begin(), sided->end());
  joints.push_back(roles.head);
  joints.push_back(roles.pelvis);
  return joints;
}

SkeletonRoles findRoles(const Skeleton& skeleton, const RoleOverrides& overrides, std::string_view source,
                        const WarningSink& warn) {
  const auto known = roleNames();
  for (const auto& [role, joint] : overrides)
    if (std::find(known.begin(), known.end(), role) == known.end())
      throw Error(fmt::format("{}: expected a role name ({}), found '{}'", source, fmt::join(known, ", "), role));

  SkeletonRoles roles;
  const auto& specs = roleSpecs();
  std::vector<std::string> normalised;
  for (const Joint& joint : skeleton.joints()) normalised.push_back(normalise(joint.name));
  auto sided = [&](std::size_t spec, std::array<int, 2>& out) {
    out[0] = findJoint(skeleton, normalised, specs[spec], Side::Left, overrides, source);
    out[1] = findJoint(skeleton, normalised, specs[spec], Side::Right, overrides, source);
  };
  sided(1, roles.wrist);
  // A capture without finger joints (a 21-joint Hips/Ab/Chest/.../LeftWrist skeleton) has
  // no fist joint: the wrist stands in, its end site (if any) becoming the fist tip below.
  std::array<bool, 2> fistFromWrist{false, false};
  for (int s = 0; s < 2; ++s) {
    const Side side = static_cast<Side>(s);
    roles.fist[s] = matchJoint(skeleton, normalised, specs[0], side, overrides, source);
    if (roles.fist[s] < 0) {
      roles.fist[s] = roles.wrist[s];
      fistFromWrist[s] = true;
    }
  }
  sided(2, roles.forearm);
  sided(3, roles.shoulder);
  sided(4, roles.ankle);
  sided(5, roles.toe);
  roles.head = findJoint(skeleton, normalised, specs[6], std::nullopt, overrides, source);
  roles.pelvis = findJoint(skeleton, normalised, specs[7], std::nullopt, overrides, source);

  const auto rest = restPositions(skeleton);
  const auto children = childLists(skeleton);
  for (int s = 0; s < 2; ++s) {
    // Farthest rest-pose point under the fist: the knuckles for CMU, the hand's end site
    // for SNU.
    const int fist = roles.fist[s];
    roles.fistTipJoint[s] = fist;
    roles.fistTipOffset[s].setZero();
    double best = 0;
    std::vector<int> stack{fist};
    while (!stack.empty()) {
      const int j = stack.back();
      stack.pop_back();
      const double d = (rest[j] - rest[fist]).norm();
      if (j != fist && d > best) {
        best = d;
        roles.fistTipJoint[s] = j;
        roles.fistTipOffset[s].setZero();
      }
      if (const auto& end = skeleton.joint(j).endSite) {
        const double e = (rest[j] + *end - rest[fist]).norm();
        if (e > best) {
          best = e;
          roles.fistTipJoint[s] = j;
          roles.fistTipOffset[s] = *end;
        }
      }
      for (int c : children[j]) stack.push_back(c);
    }
  }

  if (fistFromWrist[0] || fistFromWrist[1]) {
    std::vector<std::string> used;
    for (int s = 0; s < 2; ++s) {
      if (!fistFromWrist[s]) continue;
      const std::string& tip = skeleton.joint(static_cast<std::size_t>(roles.fistTipJoint[s])).name;
      const bool endSite = roles.fistTipOffset[s].squaredNorm() > 0;
      used.push_back(fmt::format("{}{} for {}", tip, endSite ? "'s end site" : "", roleKey(specs[0], static_cast<Side>(s))));
    }
    if (warn)
      warn(fmt::format("{}: no fist joint (a name like {}), using {}; set it with --role left_fist=JOINT", source,
                       candidates(specs[0], Side::Left).front(), fmt::join(used, " and ")));
  }

  // Rest rotations are identity, so rest positions are in the root's frame. Rest poses
  // vary (SNU's lies along +X with one leg up), so use only what holds in any of them: the
  // spine points from pelvis to head, and the hips (ankle -> knee -> hip) sit rigidly left
  // and right of the pelvis.
  Eigen::Vector3d up = rest[roles.head] - rest[roles.pelvis];
  if (up.norm() < 1e-9)
    throw Error(fmt::format("{}: expected head and pelvis apart in the rest pose, found them at the same point", source));
  up.normalize();
  auto hipOf = [&](int ankle) {
    const int knee = skeleton.joint(static_cast<std::size_t>(ankle)).parent;
    return knee > 0 ? skeleton.joint(static_cast<std::size_t>(knee)).parent : knee;
  };
  const int leftHip = hipOf(roles.ankle[0]), rightHip = hipOf(roles.ankle[1]);
  Eigen::Vector3d lateral = leftHip >= 0 && rightHip >= 0 ? Eigen::Vector3d(rest[leftHip] - rest[rightHip])
                                                          : Eigen::Vector3d(rest[roles.ankle[0]] - rest[roles.ankle[1]]);
  lateral -= lateral.dot(up) * up;
  if (lateral.norm() < 1e-9)
    throw Error(fmt::format("{}: expected left and right hips apart in the rest pose, found them level", source));
  // Avatar frame: +X to the left, +Y up, +Z forward, so Z = X x Y.
  roles.forward = lateral.normalized().cross(up).normalized();
  roles.up = up;

  for (int s = 0; s < 2; ++s) {
    const auto& end = skeleton.joint(static_cast<std::size_t>(roles.toe[s])).endSite;
    roles.toeTipOffset[s] = end ? *end : Eigen::Vector3d::Zero();
  }
  // The head top: the head's end site when it has a real length. Game exports give it none
  // or a zero-length one, and their head joint sits at the base of the skull: without a
  // stand-in the person would measure about a head short. The stand-in continues the neck by
  // a head length in proportion to the body: kHeadTopPerSpine of the rest-pose distance from
  // pelvis to head, as in CMU subject 13 (whose end site gives his known 1.63 m), and never
  // less than the neck-to-head bone.
  const Joint& head = skeleton.joint(static_cast<std::size_t>(roles.head));
  const double neckLength = roles.head > 0 ? head.offset.norm() : 0;
  if (head.endSite && head.endSite->norm() >= 0.25 * neckLength) {
    roles.headTopOffset = *head.endSite;
  } else {
    const double spine = (rest[roles.head] - rest[roles.pelvis]).norm();
    roles.headTopOffset = neckLength > 0 ? Eigen::Vector3d(head.offset.normalized() * std::max(neckLength, kHeadTopPerSpine * spine))
                                         : Eigen::Vector3d::Zero();
  }
  if (roles.head == 0) roles.headTopOffset.setZero();
  // Standing height: head top down to the lowest foot point, along the spine axis.
  const double top = (rest[roles.head] + roles.headTopOffset).dot(up);
  double bottom = top;
  for (int s = 0; s < 2; ++s)
    for (const Eigen::Vector3d& p : {rest[roles.ankle[s]], rest[roles.toe[s]], Eigen::Vector3d(rest[roles.toe[s]] + roles.toeTipOffset[s])})
      bottom = std::min(bottom, p.dot(up));
  roles.restHeight = top - bottom;
  return roles;
}

double estimateRestHeight(const Skeleton& skeleton) {
  try {
    return findRoles(skeleton).restHeight;
  } catch (const Error&) {
    return extentAlong(skeleton, restPositions(skeleton), Eigen::Vector3d::UnitY());
  }
}

}  // namespace mgrl
