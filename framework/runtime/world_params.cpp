// The world section of a scenario (paper sec. 6.6): its parameters, read and reported.
#include <string>
#include <utility>
#include <vector>

#include "mgrl/runtime/world.hpp"

namespace mgrl {

namespace {

/// A number or flag of `world:` and the WorldParams member it sets: one row serves the
/// validation (`mgrl list`), the reading and the report.
struct Field {
  ParamSpec spec;
  double WorldParams::*number = nullptr;
  bool WorldParams::*flag = nullptr;
};

Field number(double WorldParams::*member, std::string name, double fallback, double min, double max, std::string unit,
             std::string help) {
  return {ParamSpec::number(std::move(name), fallback, min, max, std::move(unit), std::move(help)), member, nullptr};
}

Field boolean(bool WorldParams::*member, std::string name, bool fallback, std::string help) {
  return {ParamSpec::boolean(std::move(name), fallback, std::move(help)), nullptr, member};
}

/// After mode, aim, top_k and margin, in `mgrl list`'s order.
const std::vector<Field>& fields() {
  using W = WorldParams;
  static const std::vector<Field> table = {
      number(&W::spacing, "spacing", 4.0, 0.5, 100, "m", "distance between neighbouring pairs on the floor"),
      number(&W::startDistance, "start_distance", 1.6, 0.3, 20, "m", "distance between sparring partners at the start"),
      number(&W::targetHold, "target_hold", 3.0, 0.1, 3600, "s", "targets mode: a target stays this long, then moves"),
      number(&W::stanceHold, "stance_hold", 0.8, 0.05, 3600, "s",
             "stances (behaviours with `stance:`): a fighter holds the stance it drew for a random time "
             "of this mean (exponential), then changes to another, drawn uniformly; 0.8 s is how long "
             "the real SNU fighters stay in a third of their facing angles"),
      number(&W::targetHeight, "target_height", -1, -1, 5, "m",
             "targets mode: target height (-1: the hitting points' centroid)"),
      number(&W::targetRadius, "target_radius", 0.12, 0.01, 2, "m", "radius of a target sphere"),
      number(&W::fistRadius, "fist_radius", 0.05, 0.005, 0.5, "m", "radius of the fist sphere"),
      number(&W::footRadius, "foot_radius", 0.06, 0.005, 0.5, "m", "radius of the toe sphere (kicks)"),
      number(&W::headRadius, "head_radius", 0.11, 0.01, 1, "m", "radius of the head capsule (head to head top)"),
      number(&W::chestRadius, "chest_radius", 0.16, 0.01, 1, "m", "radius of the chest capsule (chest to neck)"),
      number(&W::spineRadius, "spine_radius", 0.14, 0.01, 1, "m", "radius of the spine capsule (pelvis to chest)"),
      number(&W::guardRadius, "guard_radius", 0.06, 0, 0.5, "m",
             "radius of each forearm-and-glove capsule (elbow to fist tip): a strike that meets the "
             "partner's before reaching the head or body is blocked, not landed (0: nothing blocks)"),
      number(&W::bodyRadius, "body_radius", 0.2, 0, 1, "m",
             "radius of the torso capsule (pelvis to head) that keeps bodies apart: actions whose root path "
             "runs into another body are ruled out and overlaps are pushed apart (0: bodies pass through "
             "each other, as in the paper)"),
      number(&W::avoidSeconds, "avoid_seconds", 1.0, 0.1, 10, "s",
             "how far ahead an action's root path is checked against other bodies"),
      number(&W::separationSpeed, "separation_speed", 1.5, 0.1, 20, "m/s",
             "how fast overlapping bodies are pushed apart"),
      boolean(&W::plantFeet, "plant_feet", true,
              "poses: hold a foot where it landed while the capture has it on the ground (two-bone IK of "
              "hip and knee), so feet do not slide through transitions and pushes"),
      number(&W::bendPerSpeed, "bend_per_speed", 0.03, 0, 1, "m per m/s", "target bend per unit of fist speed"),
      number(&W::bendMax, "bend_max", 0.35, 0, 2, "m", "largest target bend"),
      number(&W::bendFrequency, "bend_frequency", 1.5, 0.1, 20, "Hz", "natural frequency of the target's spring"),
      number(&W::bendDamping, "bend_damping", 0.25, 0, 2, "", "damping ratio of the target's spring"),
      number(&W::reactionPerSpeed, "reaction_per_speed", 0.012, 0, 0.1, "m per m/s",
             "hit body part displacement per unit of fist speed"),
      number(&W::reactionMax, "reaction_max", 0.08, 0, 0.3, "m", "largest body part displacement"),
      number(&W::reactionSeconds, "reaction_seconds", 0.5, 0.05, 5, "s",
             "time for a hit reaction to fade (to under 10 %)"),
  };
  return table;
}

}  // namespace

const ParamSpecs& worldParamSpecs() {
  static const ParamSpecs specs = [] {
    ParamSpecs all = {
        ParamSpec::choice("mode", "sparring", {"sparring", "targets"},
                          "sparring: pairs, each avatar aims at its partner's head; targets: each avatar has its own "
                          "target, moved every target_hold seconds"),
        ParamSpec::choice("aim", "head", {"head", "chest"}, "sparring: the point of the partner an avatar aims at"),
        ParamSpec::integer("top_k", 3, 1, 64, "actions", "variety: draw among this many best actions (1: greedy)"),
        ParamSpec::number("margin", 0.1, 0, 1, "",
                          "variety: drop candidates scoring below best - margin * |best| (0: keep all k)"),
    };
    for (const Field& field : fields()) all.push_back(field.spec);
    return all;
  }();
  return specs;
}

WorldParams readWorldParams(const ConfigNode& node) {
  const Params p = Params::read(node, worldParamSpecs(), {});
  WorldParams w;
  w.mode = p.choice("mode");
  w.aim = p.choice("aim");
  w.variety = {static_cast<int>(p.integer("top_k")), p.number("margin")};
  for (const Field& field : fields()) {
    if (field.number)
      w.*field.number = p.number(field.spec.name);
    else
      w.*field.flag = p.boolean(field.spec.name);
  }
  if (w.targetHeight >= 0 && w.targetHeight < 0.05)
    p.fail("target_height", "expected -1 or a height of at least 0.05 m");
  return w;
}

nlohmann::json worldParamsJson(const WorldParams& w) {
  nlohmann::json out = {{"mode", w.mode}, {"aim", w.aim}, {"top_k", w.variety.topK}, {"margin", w.variety.margin}};
  for (const Field& field : fields()) {
    if (field.number)
      out[field.spec.name] = w.*field.number;
    else
      out[field.spec.name] = w.*field.flag;
  }
  return out;
}

const char* bodyPartName(BodyPart part) {
  switch (part) {
    case BodyPart::Spine:
      return "spine";
    case BodyPart::Chest:
      return "chest";
    case BodyPart::Head:
      return "head";
    case BodyPart::LeftArm:
      return "left_arm";
    case BodyPart::RightArm:
      return "right_arm";
  }
  return "?";
}

}  // namespace mgrl
