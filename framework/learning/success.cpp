#include "mgrl/learning/success.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "mgrl/core/error.hpp"
#include "mgrl/learning/environment_model.hpp"

namespace mgrl {

namespace {

using nlohmann::json;

// The reward's first term of a kind, null if it has none.
json rewardTerm(const json& rewardTerms, std::string_view kind) {
  if (rewardTerms.is_array())
    for (const json& t : rewardTerms)
      if (t.value("term", "") == kind) return t;
  return nullptr;
}

// The condition's parameters with the inherited ones defaulting to the reward term's values.
ParamSpecs inheritedSpecs(const ConditionRegistry::Entry& kind, const json& from) {
  ParamSpecs specs = kind.params;
  if (from.is_null()) return specs;
  for (ParamSpec& spec : specs) {
    if (std::find(kind.inherited.begin(), kind.inherited.end(), spec.name) == kind.inherited.end() ||
        !from.contains(spec.name))
      continue;
    const json& value = from[spec.name];
    const bool fits = spec.kind == ParamSpec::Kind::Choice    ? value.is_string()
                      : spec.kind == ParamSpec::Kind::Boolean ? value.is_boolean()
                                                              : value.is_number();
    if (!fits)
      throw Error(fmt::format("success term {}: {} defaults to the reward term's value; expected {}, found {}",
                              kind.name, spec.name,
                              spec.kind == ParamSpec::Kind::Choice    ? "a word"
                              : spec.kind == ParamSpec::Kind::Boolean ? "true or false"
                                                                      : "a number",
                              value.dump()));
    if (spec.kind == ParamSpec::Kind::Choice)
      spec.defaultChoice = value.get<std::string>();
    else if (spec.kind == ParamSpec::Kind::Boolean)
      spec.defaultValue = value.get<bool>() ? 1 : 0;
    else
      spec.defaultValue = value.get<double>();
  }
  return specs;
}

// One condition; `hold` allows hold_s beside its keys (the one-condition form).
std::shared_ptr<SuccessCondition> readCondition(const ConfigNode& node, const json& rewardTerms,
                                                const ConditionRegistry& kinds, bool hold) {
  if (!node.isMap() || !node.has("term"))
    node.fail(fmt::format("expected a map with 'term: <{}>', e.g. {{term: distance, within: 0.2}}",
                          fmt::join(kinds.names(), "|")));
  const ConfigNode termNode = node.child("term");
  const std::string term = termNode.asString();
  const ConditionRegistry::Entry* kind = kinds.find(term);
  if (!kind) termNode.fail(fmt::format("unknown success term {} (known: {})", quoteToken(term), kinds.describeKnown()));
  std::vector<std::string> extra{"term"};
  if (hold) extra.emplace_back("hold_s");
  const Params params = Params::read(node, inheritedSpecs(*kind, rewardTerm(rewardTerms, term)), extra);
  return node.withLocation([&] { return std::shared_ptr<SuccessCondition>(kind->make(params)); });
}

}  // namespace

SuccessCriterion SuccessCriterion::read(const ConfigNode& block, const json& rewardTerms,
                                        const ConditionRegistry& kinds) {
  if (!block.isMap())
    block.fail("expected a map such as {term: contact} or {all: [{term: distance, within: 0.2}], hold_s: 1}");
  SuccessCriterion result;
  if (block.has("all")) {
    block.allowOnly({"all", "hold_s"});
    const ConfigNode list = block.child("all");
    const std::vector<ConfigNode> all = list.elements();
    if (all.empty()) list.fail("expected at least one condition, found an empty list");
    for (const ConfigNode& c : all)
      result.conditions_.push_back({readCondition(c, rewardTerms, kinds, false), c.child("term").asString(), c});
  } else {
    result.conditions_.push_back(
        {readCondition(block, rewardTerms, kinds, true), block.child("term").asString(), block});
  }
  result.hold_s_ = block.number("hold_s", 0, 0, 3600);
  if (result.hold_s_ > 0)
    for (const Read& c : result.conditions_)
      if (c.condition->instant())
        block.child("hold_s").fail(
            fmt::format("expected no hold_s with a {} condition (it holds at single frames)", c.term));
  return result;
}

std::optional<SuccessCriterion> SuccessCriterion::implied(const json& rewardTerms, const ConditionRegistry& kinds) {
  const json contact = rewardTerm(rewardTerms, "contact");
  const ConditionRegistry::Entry* kind = kinds.find("contact");
  if (contact.is_null() || !kind) return std::nullopt;
  SuccessCriterion result;
  result.conditions_.push_back(
      {kind->make(Params::defaults(inheritedSpecs(*kind, contact))), kind->name, std::nullopt});
  return result;
}

SuccessCriterion SuccessCriterion::punch(double radius, const ConditionRegistry& kinds) {
  const ConditionRegistry::Entry* kind = kinds.find("contact");
  if (!kind) throw std::logic_error("no success term 'contact' registered");
  SuccessCriterion result;
  result.conditions_.push_back(
      {kind->make(Params::defaults(inheritedSpecs(*kind, {{"radius", radius}}))), kind->name, std::nullopt});
  return result;
}

void SuccessCriterion::bind(const StateActionModel& m) {
  for (Read& c : conditions_) {
    try {
      c.condition->bind(m);
    } catch (const ConfigError&) {
      throw;
    } catch (const KeyError& e) {
      if (!c.node) throw Error(fmt::format("success: {}: {}", e.key, e.what()));
      if (c.node->has(e.key)) c.node->child(e.key).fail(e.what());
      c.node->fail(fmt::format("{}: {}", e.key, e.what()));
    }
  }
}

std::optional<Clearance> SuccessCriterion::clearance() const {
  for (const Read& c : conditions_)
    if (std::optional<Clearance> found = c.condition->clearance()) return found;
  return std::nullopt;
}

bool SuccessCriterion::holdsAt(const StateActionModel& m, std::size_t a, std::uint32_t t, const TargetState& state,
                               const OpponentFrame* opponent) const {
  const ConditionFrame frame{m, a, t, m.actionFrameBegin[a] + t - 1, state, opponent};
  return std::all_of(conditions_.begin(), conditions_.end(), [&](const Read& c) { return c.condition->holds(frame); });
}

json SuccessCriterion::toJson() const {
  json all = json::array();
  for (const Read& c : conditions_) all.push_back(c.condition->toJson());
  return {{"all", all}, {"hold_s", hold_s_}, {"text", describe()}};
}

std::string SuccessCriterion::describe() const {
  std::vector<std::string> parts;
  for (const Read& c : conditions_) parts.push_back(c.condition->describe());
  std::string text = fmt::format("{}", fmt::join(parts, " and "));
  if (hold_s_ > 0) text += fmt::format(" for {:g} s", hold_s_);
  return text;
}

SuccessCriterion::Tracker::Tracker(const SuccessCriterion& criterion, double frameTime)
    : criterion_(&criterion),
      needed_(std::max<std::size_t>(1, static_cast<std::size_t>(std::lround(criterion.hold_s_ / frameTime)))) {}

std::uint32_t SuccessCriterion::Tracker::play(const StateActionModel& m, std::size_t a, const TargetState& e,
                                              const TrackedOpponent* opponent) {
  const auto frames = static_cast<std::uint32_t>(m.actionLength(a));
  // A learned opponent moves and strikes during the action: its head is the target at each
  // frame, facing where its root does, and its strikes are the ones it throws.
  thread_local std::vector<OpponentFrame> track;
  if (opponent) {
    opponent->track(m, a, e, track);
    if (head_ == -2) head_ = headJoint(m);
    for (std::uint32_t t = 1; t <= frames; ++t) {
      const OpponentFrame& o = track[t - 1];
      TargetState now(opponentTarget(m, o, head_, e.position.y()), 0, opponentRootAt(m, o).dyaw);
      now.opponent = e.opponent;
      held_ = criterion_->holdsAt(m, a, t, now, &o) ? held_ + 1 : 0;
      if (held_ >= needed_) return t;
    }
    return 0;
  }
  for (std::uint32_t t = 1; t <= frames; ++t) {
    TargetState now(e.at(t * m.frameTime), e.speed, e.headingAt(t * m.frameTime));
    now.turnRate = e.turnRate;
    held_ = criterion_->holdsAt(m, a, t, now) ? held_ + 1 : 0;
    if (held_ >= needed_) return t;
  }
  return 0;
}

}  // namespace mgrl
