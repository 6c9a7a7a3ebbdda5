// The reward vocabulary (scenarios/README.md, "reward terms"): a reward made of terms, each
// a signal s_k(t) in [0, 1] over the action's frames, combined as the paper combines its
// one signal (sec. 4.1: r = max_t gamma^t s(t)) or summed (r = sum_t gamma^t s(t)), with
// s(t) = sum_k w_k s_k(t). t counts frames after the decision (1 = the first). Each term
// kind is its own file (term.hpp).
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "mgrl/learning/environment_model.hpp"
#include "rewards.hpp"
#include "term.hpp"

namespace mgrl::rewards {

ParamSpec weightSpec() {
  return ParamSpec::number("weight", 1, 0, 1000, "", "w_k: the term's share of the frame's signal");
}

void bindPoint(const StateActionModel& m, BodyPoint& point) {
  std::string why;
  if (!bindBodyPoint(m, point, &why)) throw TermError("point", why);
}

BodyPoint struckPoint(const Params& p) {
  BodyPoint point = parseBodyPoint(p.choice("point"));
  if (point.kind != BodyPoint::Kind::Joint)
    p.fail("point", fmt::format("expected a role (head, left_fist, ...) or a joint, found {} (the opponent strikes "
                                "a body joint)",
                                point.name));
  return point;
}

std::shared_ptr<const StrikeReach> bindReach(const StateActionModel& m, std::uint8_t effectors, double cap) {
  try {
    return std::make_shared<const StrikeReach>(m, effectors, cap);
  } catch (const ConfigError&) {
    throw;
  } catch (const Error& e) {
    throw TermError("effector", e.what());
  }
}

namespace {

using nlohmann::json;

// One term as written: its parameters (defaults filled in, for manifests and keys), the
// term built from them and its weight.
struct ReadTerm {
  json params;
  std::unique_ptr<Term> term;
  double weight;
};

// Reads and checks the `terms` list of a block: ConfigError at the first mistake.
std::vector<ReadTerm> readTerms(const ConfigNode& block, const TermRegistry& registry) {
  if (!block.has("terms"))
    block.fail("expected a 'terms' list, e.g. terms: [{term: distance, point: pelvis, d0: 1.4}]");
  const ConfigNode list = block.child("terms");
  const std::vector<ConfigNode> elements = list.elements();
  if (elements.empty()) list.fail("expected at least one term, found an empty list");
  std::vector<ReadTerm> terms;
  for (const ConfigNode& element : elements) {
    if (!element.isMap() || !element.has("term"))
      element.fail(fmt::format("expected a map with 'term: <{}>'", fmt::join(registry.names(), "|")));
    const ConfigNode termNode = element.child("term");
    const std::string name = termNode.asString();
    const TermKind* kind = registry.find(name);
    if (!kind) termNode.fail(fmt::format("unknown term {} (known: {})", quoteToken(name), registry.describeKnown()));
    const Params params = Params::read(element, kind->params, {"term"});
    ReadTerm read{params.toJson(), element.withLocation([&] { return kind->make(params); }), params.number("weight")};
    read.params["term"] = name;
    terms.push_back(std::move(read));
  }
  return terms;
}

class Terms final : public Reward {
 public:
  Terms(const Params& p, std::vector<ReadTerm> terms) : gamma_(p.number("gamma")), sum_(p.choice("combine") == "sum") {
    if (p.block()) block_ = *p.block();
    for (ReadTerm& t : terms) {
      if (t.term->readsJoints()) joints_ = -1;
      params_.push_back(std::move(t.params));
      terms_.push_back({t.term->cost() ? -t.weight : t.weight, std::move(t.term)});
    }
  }
  std::string type() const override { return "terms"; }
  double gamma() const override { return gamma_; }

  void bind(const StateActionModel& m) override {
    for (std::size_t i = 0; i < terms_.size(); ++i) {
      try {
        terms_[i].term->bind(m);
      } catch (const TermError& e) {
        // At the term's key when the scenario wrote it, else at the term.
        if (!block_) throw Error(fmt::format("reward term {}: {}: {}", i, e.key, e.what()));
        const ConfigNode node = block_->child("terms").elements()[i];
        (node.has(e.key) ? node.child(e.key) : node).fail(e.what());
      }
    }
    if (joints_ != 0) joints_ = static_cast<std::int64_t>(m.jointNames.size());
    head_ = headJoint(m);
  }
  void bindEnvironment(const EnvironmentModel* environment) override {
    opponent_ = environment ? environment->as<TrackedOpponent>() : nullptr;
  }
  nlohmann::json terms() const override { return params_; }

  double evaluate(const StateActionModel& m, std::size_t a, const TargetState& state) const override {
    // Joint indices are the bound model's: a model with another joint count (or none) would
    // read past its arrays. (Same count, other names: not detected here; bind to the model used.)
    if (joints_ != 0 && joints_ != static_cast<std::int64_t>(m.jointNames.size()))
      throw std::logic_error("reward terms naming joints evaluated on a model they were not bound to");
    const std::size_t begin = m.actionFrameBegin[a], frames = m.actionLength(a);
    const double start = std::hypot(state.position.x(), state.position.z());  // the pelvis is at the origin at the decision
    // A learned opponent moves and strikes during the action: the terms see it frame by frame.
    thread_local std::vector<OpponentFrame> track;
    const bool tracked = opponent_ != nullptr;
    if (tracked) opponent_->track(m, a, state, track);
    double result = 0, discount = 1;
    for (std::size_t t = 1; t <= frames; ++t) {
      discount *= gamma_;
      Eigen::Vector3d e;
      const OpponentFrame* opponent = nullptr;
      if (tracked) {
        opponent = &track[t - 1];
        e = opponentTarget(m, *opponent, head_, state.position.y());
      } else {
        e = state.at(static_cast<double>(t) * m.frameTime);  // where a moving target is at frame t
      }
      const TermFrame frame{m, a, t, begin + t - 1, e, state, start, opponent};
      double signal = 0;
      for (const Weighted& term : terms_) signal += term.weight * term.term->signal(frame);
      result = sum_ ? result + discount * signal : std::max(result, discount * signal);
    }
    return result;
  }

 private:
  struct Weighted {
    double weight;
    std::unique_ptr<Term> term;
  };
  double gamma_;
  bool sum_;
  std::vector<Weighted> terms_;
  json params_ = json::array();      ///< each term as written, defaults filled in
  std::optional<ConfigNode> block_;  ///< the reward's YAML block, for bind()'s messages
  /// 0 if no term names a joint; else the bound model's joint count, -1 before bind().
  std::int64_t joints_ = 0;
  int head_ = -1;  ///< the bound model's head joint, for a learned opponent's target
  const TrackedOpponent* opponent_ = nullptr;  ///< the environment's learned opponent, if it has one
};

}  // namespace

void registerTerms(RewardRegistry& registry, const TermRegistry& terms) {
  RewardRegistry::Entry entry{
      "terms",
      "a list of reward terms (below), each a signal over the action's frames; "
      "combine: max gives max_t gamma^t sum_k w_k s_k(t) (paper sec. 4.1), sum gives the sum over t",
      {ParamSpec::choice("combine", "max", {"max", "sum"},
                         "max: the best discounted frame (the paper's); sum: every frame's discounted signal"),
       ParamSpec::number("gamma", 0.97, 1e-6, 1, "per frame", "discount per frame, inside and after the action")},
      [kinds = &terms](const Params& p) { return std::make_unique<Terms>(p, readTerms(*p.block(), *kinds)); }};
  entry.blockKeys = {"terms"};
  entry.readBlock = [kinds = &terms](const ConfigNode& block) {
    nlohmann::json list = nlohmann::json::array();
    for (const ReadTerm& t : readTerms(block, *kinds)) list.push_back(t.params);
    return nlohmann::json{{"terms", list}};
  };
  entry.example = "{type: terms, terms: [{term: distance, point: pelvis, d0: 1.4}]}";
  registry.add(std::move(entry));
}

}  // namespace mgrl::rewards
