#include "mgrl/learning/success.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>
#include <fmt/ranges.h>

namespace mgrl {

namespace {

using nlohmann::json;

constexpr double kDegree = std::numbers::pi / 180;

// The reward's first term of a kind as {"term": ..., params...}: the vocabulary's own, or
// what the paper's presets amount to. Null if the reward has none.
json rewardTerm(const json& reward, std::string_view kind) {
  const std::string type = reward.value("type", "");
  if (type == "terms" && reward.contains("terms"))
    for (const json& t : reward["terms"])
      if (t.value("term", "") == kind) return t;
  if (type == "approach" && kind == "distance") return {{"term", "distance"}, {"point", "centroid"}, {"dims", 2}, {"d0", 0}};
  if (type == "hit" && kind == "contact")
    return {{"term", "contact"}, {"effector", "fists"}, {"radius", reward.value("contact_radius", 0.15)}};
  return nullptr;
}

// Keys of a condition: ConfigError at the first one not allowed.
void allowKeys(const ConfigNode& node, std::vector<std::string_view> allowed, bool hold) {
  if (hold) allowed.push_back("hold_s");
  for (const std::string& key : node.keys())
    if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
      node.child(key).fail(fmt::format("unknown key (expected one of: {})", fmt::join(allowed, ", ")));
}

// A key a condition may leave out, from the reward's term of its kind, else `fallback`.
template <class T>
T inherited(const json& from, const char* key, T fallback) {
  return from.is_null() ? fallback : from.value(key, fallback);
}

// A word the condition writes, else the reward term's, else `fallback`.
std::string word(const ConfigNode& node, const json& from, const char* key, const char* fallback) {
  return node.has(key) ? node.child(key).asString() : inherited(from, key, std::string(fallback));
}

// The condition's body point (written, from the reward, else `fallback`) and where it is
// written: its key, or the condition that takes it from the reward.
void readPoint(const ConfigNode& node, const json& from, const char* fallback, SuccessCondition& c) {
  const std::string point = word(node, from, "point", fallback);
  c.point = node.withLocation([&] { return parseBodyPoint(point); });
  c.pointWritten = node.has("point");
  c.pointNode = c.pointWritten ? node.child("point") : node;
}

std::uint8_t readEffector(const ConfigNode& node, const json& from) {
  const std::string effector = word(node, from, "effector", "fists");
  return node.withLocation([&] { return parseEffector(effector); });
}

// One condition; `hold` allows hold_s beside its keys (the one-condition form).
SuccessCondition readCondition(const ConfigNode& node, const json& reward, bool hold) {
  if (!node.isMap() || !node.has("term"))
    node.fail("expected a map with 'term: <contact|distance|facing|avoid>', e.g. {term: distance, within: 0.2}");
  const ConfigNode termNode = node.child("term");
  const std::string term = termNode.asString();
  const json from = rewardTerm(reward, term);
  SuccessCondition c;
  if (term == "contact") {
    allowKeys(node, {"term", "effector", "radius"}, hold);
    c.kind = SuccessCondition::Kind::Contact;
    c.effectors = readEffector(node, from);
    c.radius = node.number("radius", inherited(from, "radius", 0.15), 1e-4, 10);
  } else if (term == "distance") {
    allowKeys(node, {"term", "point", "dims", "d0", "within"}, hold);
    c.kind = SuccessCondition::Kind::Distance;
    readPoint(node, from, "centroid", c);
    if (c.point.kind == BodyPoint::Kind::Body)
      c.pointNode->fail(fmt::format("{}expected centroid, pelvis, a role or a joint, found body",
                                    c.pointWritten ? "" : "point: "));
    c.dims = static_cast<int>(node.integer("dims", inherited(from, "dims", 2), 2, 3));
    if (c.dims == 3 && c.point.kind == BodyPoint::Kind::Pelvis)
      node.fail("dims: expected 2 with point: pelvis (a ground point has no height), found 3");
    c.d0 = node.number("d0", inherited(from, "d0", 0.0), 0, 100);
    c.within = node.number("within", 0.2, 0, 100);
  } else if (term == "facing") {
    allowKeys(node, {"term", "angle_deg", "within_deg"}, hold);
    c.kind = SuccessCondition::Kind::Facing;
    c.angle = node.number("angle_deg", inherited(from, "angle_deg", 0.0), 0, 180) * kDegree;
    c.withinAngle = node.number("within_deg", 30, 0, 180) * kDegree;
  } else if (term == "avoid") {
    allowKeys(node, {"term", "point", "effector", "clear", "body_radius"}, hold);
    c.kind = SuccessCondition::Kind::Avoid;
    readPoint(node, from, "head", c);
    if (c.point.kind != BodyPoint::Kind::Joint)
      c.pointNode->fail(fmt::format("{}expected a role (head, ...) or a joint, found {}", c.pointWritten ? "" : "point: ",
                                    c.point.name));
    c.effectors = readEffector(node, from);
    c.effectorNode = node.has("effector") ? node.child("effector") : node;
    c.clear = node.number("clear", 0.1, 0, 0.95);
    c.bodyRadius = node.number("body_radius", inherited(from, "body_radius", 0.2), 0, 1);
  } else {
    termNode.fail(fmt::format("unknown success term {} (known: contact, distance, facing, avoid)", quoteToken(term)));
  }
  return c;
}

std::string describeCondition(const SuccessCondition& c) {
  static const std::pair<std::uint8_t, const char*> kNames[] = {
      {kAnyLimb, "any limb"}, {kFists, "the fists"}, {kFeet, "the feet"},         {kLeftFist, "the left fist"},
      {kRightFist, "the right fist"}, {kLeftFoot, "the left foot"}, {kRightFoot, "the right foot"}};
  switch (c.kind) {
    case SuccessCondition::Kind::Contact: {
      std::string who = "some limbs";
      for (const auto& [bits, name] : kNames)
        if (bits == c.effectors) who = name;
      return fmt::format("an effective strike of {} within {:g} m", who, c.radius);
    }
    case SuccessCondition::Kind::Distance:
      return fmt::format("the {} within {:g} m of {:g} m from the target{}", bodyPointName(c.point), c.within, c.d0,
                         c.dims == 3 ? " (3-D)" : "");
    case SuccessCondition::Kind::Facing:
      return fmt::format("facing within {:g} deg of {:g} deg off the target", c.withinAngle / kDegree,
                         c.angle / kDegree);
    case SuccessCondition::Kind::Avoid:
      return fmt::format("the {} at least {:g} m from the opponent's strikes and body", bodyPointName(c.point), c.clear);
  }
  return {};
}

}  // namespace

SuccessCriterion SuccessCriterion::read(const ConfigNode& block, const json& reward) {
  if (!block.isMap())
    block.fail("expected a map such as {term: contact} or {all: [{term: distance, within: 0.2}], hold_s: 1}");
  SuccessCriterion result;
  if (block.has("all")) {
    block.allowOnly({"all", "hold_s"});
    const ConfigNode list = block.child("all");
    const std::vector<ConfigNode> all = list.elements();
    if (all.empty()) list.fail("expected at least one condition, found an empty list");
    for (const ConfigNode& c : all) result.conditions_.push_back(readCondition(c, reward, false));
  } else {
    result.conditions_.push_back(readCondition(block, reward, true));
  }
  result.hold_s_ = block.number("hold_s", 0, 0, 3600);
  if (result.hold_s_ > 0)
    for (const SuccessCondition& c : result.conditions_)
      if (c.kind == SuccessCondition::Kind::Contact)
        block.child("hold_s").fail("expected no hold_s with a contact condition (a strike lands at one frame)");
  return result;
}

std::optional<SuccessCriterion> SuccessCriterion::implied(const json& reward) {
  const json contact = rewardTerm(reward, "contact");
  if (contact.is_null()) return std::nullopt;
  SuccessCriterion result;
  SuccessCondition c;
  c.effectors = parseEffector(contact.value("effector", std::string("fists")));
  c.radius = contact.value("radius", 0.15);
  result.conditions_.push_back(c);
  return result;
}

SuccessCriterion SuccessCriterion::punch(double radius) {
  SuccessCriterion result;
  SuccessCondition c;
  c.radius = radius;
  result.conditions_.push_back(c);
  return result;
}

void SuccessCriterion::bind(const StateActionModel& m) {
  for (SuccessCondition& c : conditions_) {
    std::string why;
    if (c.kind == SuccessCondition::Kind::Avoid) {
      // The opponent is an avatar of this graph: its strikes are this model's. The field
      // reaches a little past `clear` so "at least clear" is read from exact distances. A
      // capture without the effector's strikes is refused where the effector is written.
      if (!c.effectorNode) throw std::logic_error("an avoid condition not read from YAML");
      c.reach = c.effectorNode->withLocation(
          [&] { return std::make_shared<const StrikeReach>(m, c.effectors, std::min(1.0, c.clear + 0.05)); });
    }
    if ((c.kind != SuccessCondition::Kind::Distance && c.kind != SuccessCondition::Kind::Avoid) ||
        bindBodyPoint(m, c.point, &why))
      continue;
    if (c.pointNode) c.pointNode->fail(c.pointWritten ? why : fmt::format("point: {}", why));
    throw Error(fmt::format("success: point: {}", why));
  }
}

bool SuccessCriterion::holdsAt(const StateActionModel& m, std::size_t a, std::uint32_t t,
                               const TargetState& state) const {
  const std::size_t frame = m.actionFrameBegin[a] + t - 1;
  const Eigen::Vector3d& e = state.position;
  for (const SuccessCondition& c : conditions_) {
    switch (c.kind) {
      case SuccessCondition::Kind::Contact:
        if (strikeAt(m, a, t, c.effectors, c.radius, false, e) <= 0) return false;
        break;
      case SuccessCondition::Kind::Distance:
        if (c.point.kind == BodyPoint::Kind::Joint &&
            (c.point.joint < 0 || static_cast<std::size_t>(c.point.joint) >= m.jointNames.size()))
          throw std::logic_error("a success condition naming a joint used before bind()");
        if (std::abs(bodyDistance(m, frame, c.point, c.dims, e) - c.d0) > c.within) return false;
        break;
      case SuccessCondition::Kind::Facing:
        if (std::abs(facingError(m, frame, e) - c.angle) > c.withinAngle) return false;
        break;
      case SuccessCondition::Kind::Avoid:
        if (!c.reach || c.point.joint < 0 || static_cast<std::size_t>(c.point.joint) >= m.jointNames.size())
          throw std::logic_error("an avoid success condition used before bind()");
        if (opponentClearance(m, frame, c.point.joint, *c.reach, state, c.bodyRadius) < c.clear) return false;
        break;
    }
  }
  return true;
}

json SuccessCriterion::toJson() const {
  json all = json::array();
  for (const SuccessCondition& c : conditions_) {
    switch (c.kind) {
      case SuccessCondition::Kind::Contact:
        all.push_back({{"term", "contact"}, {"effectors", c.effectors}, {"radius", c.radius}});
        break;
      case SuccessCondition::Kind::Distance:
        all.push_back({{"term", "distance"},
                       {"point", bodyPointName(c.point)},
                       {"dims", c.dims},
                       {"d0", c.d0},
                       {"within", c.within}});
        break;
      case SuccessCondition::Kind::Facing:
        all.push_back({{"term", "facing"}, {"angle_deg", c.angle / kDegree}, {"within_deg", c.withinAngle / kDegree}});
        break;
      case SuccessCondition::Kind::Avoid:
        all.push_back({{"term", "avoid"},
                       {"point", bodyPointName(c.point)},
                       {"effectors", c.effectors},
                       {"clear", c.clear},
                       {"body_radius", c.bodyRadius}});
        break;
    }
  }
  return {{"all", all}, {"hold_s", hold_s_}, {"text", describe()}};
}

std::string SuccessCriterion::describe() const {
  std::vector<std::string> parts;
  for (const SuccessCondition& c : conditions_) parts.push_back(describeCondition(c));
  std::string text = fmt::format("{}", fmt::join(parts, " and "));
  if (hold_s_ > 0) text += fmt::format(" for {:g} s", hold_s_);
  return text;
}

SuccessCriterion::Tracker::Tracker(const SuccessCriterion& criterion, double frameTime)
    : criterion_(&criterion),
      needed_(std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(criterion.hold_s_ / frameTime)))) {}

std::uint32_t SuccessCriterion::Tracker::play(const StateActionModel& m, std::size_t a, const TargetState& e) {
  const auto frames = static_cast<std::uint32_t>(m.actionLength(a));
  for (std::uint32_t t = 1; t <= frames; ++t) {
    const TargetState now(e.at(t * m.frameTime), e.speed, e.heading);
    held_ = criterion_->holdsAt(m, a, t, now) ? held_ + 1 : 0;
    if (held_ >= needed_) return t;
  }
  return 0;
}

}  // namespace mgrl
