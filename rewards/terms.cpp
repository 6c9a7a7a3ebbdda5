// The reward vocabulary (scenarios/README.md, "reward terms"): a reward made of terms, each
// a signal s_k(t) in [0, 1] over the action's frames, combined as the paper combines its
// one signal (sec. 4.1: r = max_t gamma^t s(t)) or summed (r = sum_t gamma^t s(t)), with
// s(t) = sum_k w_k s_k(t). t counts frames after the decision (1 = the first).
#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "mgrl/learning/signals.hpp"
#include "rewards.hpp"

namespace mgrl::rewards {

namespace {

using nlohmann::json;

constexpr double kDegree = std::numbers::pi / 180;
const BodyPoint kPelvis = BodyPoint::pelvis();

ParamSpec weightSpec() {
  return ParamSpec::number("weight", 1, 0, 1000, "", "w_k: the term's share of the frame's signal");
}


const TermKind* findKind(std::string_view name) {
  for (const TermKind& k : termKinds())
    if (name == k.name) return &k;
  return nullptr;
}

// Reads and checks the `terms` list of a block: ConfigError at the first mistake. Returns
// each term's parameters, defaults filled in.
std::vector<json> readTerms(const ConfigNode& block) {
  if (!block.has("terms"))
    block.fail("expected a 'terms' list, e.g. terms: [{term: distance, point: pelvis, d0: 1.4}]");
  const ConfigNode list = block.child("terms");
  const std::vector<ConfigNode> elements = list.elements();
  if (elements.empty()) list.fail("expected at least one term, found an empty list");
  std::vector<std::string> names;
  for (const TermKind& k : termKinds()) names.push_back(k.name);
  std::vector<json> terms;
  for (const ConfigNode& element : elements) {
    if (!element.isMap() || !element.has("term"))
      element.fail(fmt::format("expected a map with 'term: <{}>'", fmt::join(names, "|")));
    const ConfigNode termNode = element.child("term");
    const std::string name = termNode.asString();
    const TermKind* kind = findKind(name);
    if (!kind) termNode.fail(fmt::format("unknown term {} (known: {})", quoteToken(name), fmt::join(names, ", ")));
    const Params params = Params::read(element, kind->params, {"term"});
    if (name == "effort" && params.given("point") && params.choice("point") == "centroid")
      params.fail("point", "expected pelvis (root speed), body (every joint's mean speed), a role or a joint, found "
                           "centroid (the centroid is carried along rigidly; its speed is the root's)");
    if (name == "distance" && params.choice("point") == "body")
      params.fail("point", "expected centroid, pelvis, a role or a joint, found body (body is for effort only)");
    if (name == "avoid") {
      const std::string point = params.choice("point");
      if (point == "centroid" || point == "pelvis" || point == "body")
        params.fail("point", fmt::format("expected a role (head, left_fist, ...) or a joint, found {} (the opponent "
                                         "strikes a body joint)",
                                         point));
    }
    if (name == "distance" && params.choice("point") == "pelvis" && params.integer("dims") == 3)
      params.fail("dims", "expected 2 with point: pelvis (a ground point has no height), found 3");
    json term = params.toJson();
    term["term"] = name;
    terms.push_back(std::move(term));
  }
  return terms;
}

class Terms final : public Reward {
 public:
  Terms(const Params& p, const std::vector<json>& terms)
      : gamma_(p.number("gamma")), sum_(p.choice("combine") == "sum") {
    if (p.block()) block_ = *p.block();
    for (const json& t : terms) {
      Term term;
      const std::string name = t["term"];
      term.weight = t["weight"];
      if (name == "distance") {
        term.kind = Kind::Distance;
        term.point = parseBodyPoint(t["point"].get<std::string>());
        term.dims = t["dims"];
        term.target = t["d0"];
        term.scale = t["sigma"];
      } else if (name == "facing") {
        term.kind = Kind::Facing;
        term.target = t["angle_deg"].get<double>() * kDegree;
        term.scale = t["sigma_deg"].get<double>() * kDegree;
      } else if (name == "contact") {
        term.kind = Kind::Contact;
        term.effectors = parseEffector(t["effector"].get<std::string>());
        term.scale = t["radius"];
        term.useSpeed = t["use_speed"];
      } else if (name == "avoid") {
        term.kind = Kind::Avoid;
        term.point = parseBodyPoint(t["point"].get<std::string>());
        term.effectors = parseEffector(t["effector"].get<std::string>());
        term.scale = t["clear"];
        term.target = t["body_radius"];
      } else if (name == "travel") {
        term.kind = Kind::Travel;
        term.sign = t["direction"] == "toward" ? 1 : -1;
        term.scale = t["scale_m"];
      } else {
        term.kind = Kind::Effort;
        term.scale = t["speed_mps"];
        term.point = parseBodyPoint(t["point"].get<std::string>());
      }
      terms_.push_back(term);
      if (term.point.kind == BodyPoint::Kind::Joint || term.point.kind == BodyPoint::Kind::Body) joints_ = -1;
    }
  }
  std::string type() const override { return "terms"; }
  double gamma() const override { return gamma_; }

  void bind(const StateActionModel& m) override {
    for (std::size_t i = 0; i < terms_.size(); ++i) {
      std::string why;
      if (bindBodyPoint(m, terms_[i].point, &why)) continue;
      if (!block_) throw Error(fmt::format("reward term {}: point: {}", i, why));
      block_->child("terms").elements()[i].child("point").fail(why);
    }
    // avoid: the opponent is an avatar of this graph, so its strikes are this model's.
    for (std::size_t i = 0; i < terms_.size(); ++i) {
      Term& term = terms_[i];
      if (term.kind != Kind::Avoid) continue;
      try {
        term.reach = std::make_shared<const StrikeReach>(m, term.effectors, term.scale);
      } catch (const ConfigError&) {
        throw;
      } catch (const Error& e) {
        if (!block_) throw Error(fmt::format("reward term {}: effector: {}", i, e.what()));
        const ConfigNode node = block_->child("terms").elements()[i];
        (node.has("effector") ? node.child("effector") : node).fail(e.what());
      }
    }
    if (joints_ != 0) joints_ = static_cast<std::int64_t>(m.jointNames.size());
  }

  double evaluate(const StateActionModel& m, std::size_t a, const TargetState& state) const override {
    // Joint indices are the bound model's: a model with another joint count (or none) would
    // read past its arrays. (Same count, other names: not detected here; bind to the model used.)
    if (joints_ != 0 && joints_ != static_cast<std::int64_t>(m.jointNames.size()))
      throw std::logic_error("reward terms naming joints evaluated on a model they were not bound to");
    const std::size_t begin = m.actionFrameBegin[a], frames = m.actionLength(a);
    const double start = std::hypot(state.position.x(), state.position.z());  // the pelvis is at the origin at the decision
    double result = 0, discount = 1;
    for (std::size_t t = 1; t <= frames; ++t) {
      discount *= gamma_;
      const std::size_t frame = begin + t - 1;
      const Eigen::Vector3d e = state.at(static_cast<double>(t) * m.frameTime);  // where a moving target is at frame t
      double signal = 0;
      for (const Term& term : terms_) {
        double s = 0;
        switch (term.kind) {
          case Kind::Distance:
            s = std::exp(-std::abs(bodyDistance(m, frame, term.point, term.dims, e) - term.target) / term.scale);
            break;
          case Kind::Facing:
            s = std::exp(-std::abs(facingError(m, frame, e) - term.target) / term.scale);
            break;
          case Kind::Contact:
            s = strikeAt(m, a, static_cast<std::uint32_t>(t), term.effectors, term.scale, term.useSpeed, e);
            break;
          case Kind::Travel: {
            const double progress = term.sign * (start - bodyDistance(m, frame, kPelvis, 2, e));
            s = std::clamp(progress / term.scale, 0.0, 1.0);
            break;
          }
          case Kind::Avoid:
            // 0 with the body point on a strike tip of the opponent (or the bodies
            // overlapping), 1 from `clear` away.
            if (!term.reach) throw std::logic_error("an avoid term evaluated before bind()");
            s = opponentClearance(m, frame, term.point.joint, *term.reach, state, term.target) / term.scale;
            break;
          case Kind::Effort:
            s = std::exp(-(term.point.kind == BodyPoint::Kind::Pelvis ? rootSpeed(m, a, t) : bodySpeed(m, frame, term.point)) /
                         term.scale);
            break;
        }
        signal += term.weight * s;
      }
      result = sum_ ? result + discount * signal : std::max(result, discount * signal);
    }
    return result;
  }

 private:
  enum class Kind { Distance, Facing, Contact, Travel, Effort, Avoid };
  struct Term {
    Kind kind = Kind::Distance;
    double weight = 1;
    /// target: distance d0, facing angle, avoid body_radius; scale: distance sigma, facing
    /// sigma, contact radius, travel scale_m, effort speed_mps, avoid clear.
    double target = 0, scale = 1;
    BodyPoint point;
    int dims = 2, sign = 1;
    std::uint8_t effectors = kFists;
    bool useSpeed = true;
    std::shared_ptr<const StrikeReach> reach;  ///< avoid, after bind()
  };
  double gamma_;
  bool sum_;
  std::vector<Term> terms_;
  std::optional<ConfigNode> block_;  ///< the reward's YAML block, for bind()'s messages
  /// 0 if no term names a joint; else the bound model's joint count, -1 before bind().
  std::int64_t joints_ = 0;
};

}  // namespace

const std::vector<TermKind>& termKinds() {
  static const std::vector<TermKind> kinds = {
      {"distance", "exp(-|d - d0| / sigma), d the distance from a body point to the target",
       {ParamSpec::choiceOrName("point", "centroid", {"centroid", "pelvis"}, "a skeleton role or joint",
                                "centroid: the effective hitting points' centroid (the paper's); pelvis: the ground "
                                "point below the root; a role (left_fist, right_toe, head, ...) or a joint's name "
                                "(LeftHand): that joint"),
        ParamSpec::integer("dims", 2, 2, 3, "", "2: distance on the ground; 3: in space (not with pelvis)"),
        ParamSpec::number("d0", 0, 0, 100, "m", "preferred distance"),
        ParamSpec::number("sigma", 0.1, 1e-4, 100, "m", "distance scale of the exponential"), weightSpec()}},
      {"facing", "exp(-|angle - angle0| / sigma), angle between the avatar's facing and the target's direction",
       {ParamSpec::number("angle_deg", 0, 0, 180, "deg", "preferred angle (0: target straight ahead)"),
        ParamSpec::number("sigma_deg", 30, 0.1, 360, "deg", "angle scale of the exponential"), weightSpec()}},
      {"contact", "an effective strike of the effector within radius of the target, weighted by its speed",
       {ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                          "which limbs' effective strikes count (feet: effective kicks)"),
        ParamSpec::number("radius", 0.15, 1e-4, 10, "m", "a strike counts when its tip is this close to the target"),
        ParamSpec::boolean("use_speed", true, "weight a strike by its normalised speed (false: 1)"), weightSpec()}},
      {"travel", "clamp(progress / scale_m, 0, 1): ground progress toward (or away from) the target since the decision",
       {ParamSpec::choice("direction", "toward", {"toward", "away"}, "which way counts as progress"),
        ParamSpec::number("scale_m", 1, 1e-3, 100, "m", "progress that earns the full signal"), weightSpec()}},
      {"effort", "exp(-v / speed_mps), v the avatar's ground speed or a joint's speed: economy, standing still earns 1",
       {ParamSpec::number("speed_mps", 1, 1e-3, 100, "m/s", "speed scale of the exponential"),
        ParamSpec::choiceOrName("point", "pelvis", {"pelvis", "body"}, "a skeleton role or joint",
                                "pelvis: the root's ground speed; body: the mean speed of every joint in the "
                                "capture; a role or a joint's name: that joint's speed"),
        weightSpec()}},
      {"avoid",
       "min(d / clear, 1), d the distance from a body point to the nearest tip of the opponent's effective strikes, "
       "or the gap between the two bodies if smaller (the opponent environment: an avatar of the same graph at the "
       "target, facing its heading)",
       {ParamSpec::choiceOrName("point", "head", {"head"}, "a skeleton role or joint",
                                "the body point the opponent must not reach: a role (head, left_shoulder, ...) or a "
                                "joint's name"),
        ParamSpec::choice("effector", "fists", {std::begin(kEffectorNames), std::end(kEffectorNames)},
                          "whose strikes the opponent throws (feet: its effective kicks)"),
        ParamSpec::number("clear", 0.3, 0.01, 1, "m", "distance from every strike tip that earns the full signal"),
        ParamSpec::number("body_radius", 0.2, 0, 1, "m",
                          "each body's ground radius: the bodies count as reached when the pelvis is within two of "
                          "them of the opponent (as the world's body_radius)"),
        weightSpec()}},
  };
  return kinds;
}

void registerTerms(RewardRegistry& registry) {
  RewardRegistry::Entry entry{
      "terms",
      "a list of terms (distance, facing, contact, travel, effort, avoid), each a signal over the action's frames; "
      "combine: max gives max_t gamma^t sum_k w_k s_k(t) (paper sec. 4.1), sum gives the sum over t",
      {ParamSpec::choice("combine", "max", {"max", "sum"},
                         "max: the best discounted frame (the paper's); sum: every frame's discounted signal"),
       ParamSpec::number("gamma", 0.97, 1e-6, 1, "per frame", "discount per frame, inside and after the action")},
      [](const Params& p) { return std::make_unique<Terms>(p, readTerms(*p.block())); }};
  entry.blockKeys = {"terms"};
  entry.readBlock = [](const ConfigNode& block) { return json{{"terms", readTerms(block)}}; };
  entry.example = "{type: terms, terms: [{term: distance, point: pelvis, d0: 1.4}]}";
  registry.add(std::move(entry));
}

std::string describeTerms(std::string_view indent) {
  std::string out;
  for (const TermKind& k : termKinds()) {
    out += fmt::format("{}term: {}  {}\n", indent, k.name, k.summary);
    out += describeParams(k.params, fmt::format("{}  ", indent));
  }
  return out;
}

}  // namespace mgrl::rewards
