// The world section of a scenario (paper sec. 6.6): its parameters, read and reported.
#include <fmt/format.h>

#include "mgrl/runtime/world.hpp"

namespace mgrl {

const ParamSpecs& worldParamSpecs() {
  static const ParamSpecs specs = {
      ParamSpec::choice("mode", "sparring", {"sparring", "targets"},
                        "sparring: pairs, each avatar aims at its partner's head; targets: each avatar has its own "
                        "target, moved every target_hold seconds"),
      ParamSpec::choice("aim", "head", {"head", "chest"}, "sparring: the point of the partner an avatar aims at"),
      ParamSpec::integer("top_k", 3, 1, 64, "actions", "variety: draw among this many best actions (1: greedy)"),
      ParamSpec::number("margin", 0.1, 0, 1, "",
                        "variety: drop candidates scoring below best - margin * |best| (0: keep all k)"),
      ParamSpec::number("spacing", 4.0, 0.5, 100, "m", "distance between neighbouring pairs on the floor"),
      ParamSpec::number("start_distance", 1.6, 0.3, 20, "m", "distance between sparring partners at the start"),
      ParamSpec::number("target_hold", 3.0, 0.1, 3600, "s", "targets mode: a target stays this long, then moves"),
      ParamSpec::number("stance_hold", 0.8, 0.05, 3600, "s",
                        "stances (behaviours with `stance:`): a fighter holds the stance it drew for a random time "
                        "of this mean (exponential), then changes to another, drawn uniformly; 0.8 s is how long "
                        "the real SNU fighters stay in a third of their facing angles"),
      ParamSpec::number("target_height", -1, -1, 5, "m",
                        "targets mode: target height (-1: the hitting points' centroid)"),
      ParamSpec::number("target_radius", 0.12, 0.01, 2, "m", "radius of a target sphere"),
      ParamSpec::number("fist_radius", 0.05, 0.005, 0.5, "m", "radius of the fist sphere"),
      ParamSpec::number("foot_radius", 0.06, 0.005, 0.5, "m", "radius of the toe sphere (kicks)"),
      ParamSpec::number("head_radius", 0.11, 0.01, 1, "m", "radius of the head capsule (head to head top)"),
      ParamSpec::number("chest_radius", 0.16, 0.01, 1, "m", "radius of the chest capsule (chest to neck)"),
      ParamSpec::number("spine_radius", 0.14, 0.01, 1, "m", "radius of the spine capsule (pelvis to chest)"),
      ParamSpec::number("guard_radius", 0.06, 0, 0.5, "m",
                        "radius of each forearm-and-glove capsule (elbow to fist tip): a strike that meets the "
                        "partner's before reaching the head or body is blocked, not landed (0: nothing blocks)"),
      ParamSpec::number("body_radius", 0.2, 0, 1, "m",
                        "radius of the torso capsule (pelvis to head) that keeps bodies apart: actions whose root path "
                        "runs into another body are ruled out and overlaps are pushed apart (0: bodies pass through "
                        "each other, as in the paper)"),
      ParamSpec::number("avoid_seconds", 1.0, 0.1, 10, "s",
                        "how far ahead an action's root path is checked against other bodies"),
      ParamSpec::number("separation_speed", 1.5, 0.1, 20, "m/s", "how fast overlapping bodies are pushed apart"),
      ParamSpec::boolean("plant_feet", true,
                         "poses: hold a foot where it landed while the capture has it on the ground (two-bone IK of "
                         "hip and knee), so feet do not slide through transitions and pushes"),
      ParamSpec::number("bend_per_speed", 0.03, 0, 1, "m per m/s", "target bend per unit of fist speed"),
      ParamSpec::number("bend_max", 0.35, 0, 2, "m", "largest target bend"),
      ParamSpec::number("bend_frequency", 1.5, 0.1, 20, "Hz", "natural frequency of the target's spring"),
      ParamSpec::number("bend_damping", 0.25, 0, 2, "", "damping ratio of the target's spring"),
      ParamSpec::number("reaction_per_speed", 0.012, 0, 0.1, "m per m/s",
                        "hit body part displacement per unit of fist speed"),
      ParamSpec::number("reaction_max", 0.08, 0, 0.3, "m", "largest body part displacement"),
      ParamSpec::number("reaction_seconds", 0.5, 0.05, 5, "s", "time for a hit reaction to fade (to under 10 %)"),
  };
  return specs;
}

WorldParams readWorldParams(const ConfigNode& node) {
  const Params p = Params::read(node, worldParamSpecs(), {});
  WorldParams w;
  w.mode = p.choice("mode");
  w.variety = {static_cast<int>(p.integer("top_k")), p.number("margin")};
  w.spacing = p.number("spacing");
  w.startDistance = p.number("start_distance");
  w.targetHold = p.number("target_hold");
  w.stanceHold = p.number("stance_hold");
  w.targetHeight = p.number("target_height");
  w.targetRadius = p.number("target_radius");
  w.fistRadius = p.number("fist_radius");
  w.footRadius = p.number("foot_radius");
  w.aim = p.choice("aim");
  w.headRadius = p.number("head_radius");
  w.chestRadius = p.number("chest_radius");
  w.guardRadius = p.number("guard_radius");
  w.spineRadius = p.number("spine_radius");
  w.bodyRadius = p.number("body_radius");
  w.avoidSeconds = p.number("avoid_seconds");
  w.separationSpeed = p.number("separation_speed");
  w.plantFeet = p.boolean("plant_feet");
  w.bendPerSpeed = p.number("bend_per_speed");
  w.bendMax = p.number("bend_max");
  w.bendFrequency = p.number("bend_frequency");
  w.bendDamping = p.number("bend_damping");
  w.reactionPerSpeed = p.number("reaction_per_speed");
  w.reactionMax = p.number("reaction_max");
  w.reactionSeconds = p.number("reaction_seconds");
  if (w.targetHeight >= 0 && w.targetHeight < 0.05) p.fail("target_height", "expected -1 or a height of at least 0.05 m");
  return w;
}

nlohmann::json worldParamsJson(const WorldParams& w) {
  return {{"mode", w.mode},
          {"top_k", w.variety.topK},
          {"margin", w.variety.margin},
          {"spacing", w.spacing},
          {"start_distance", w.startDistance},
          {"target_hold", w.targetHold},
          {"stance_hold", w.stanceHold},
          {"target_height", w.targetHeight},
          {"target_radius", w.targetRadius},
          {"fist_radius", w.fistRadius},
          {"foot_radius", w.footRadius},
          {"aim", w.aim},
          {"head_radius", w.headRadius},
          {"chest_radius", w.chestRadius},
          {"spine_radius", w.spineRadius},
          {"guard_radius", w.guardRadius},
          {"body_radius", w.bodyRadius},
          {"avoid_seconds", w.avoidSeconds},
          {"separation_speed", w.separationSpeed},
          {"plant_feet", w.plantFeet},
          {"bend_per_speed", w.bendPerSpeed},
          {"bend_max", w.bendMax},
          {"bend_frequency", w.bendFrequency},
          {"bend_damping", w.bendDamping},
          {"reaction_per_speed", w.reactionPerSpeed},
          {"reaction_max", w.reactionMax},
          {"reaction_seconds", w.reactionSeconds}};
}

const char* bodyPartName(BodyPart part) {
  switch (part) {
    case BodyPart::Spine: return "spine";
    case BodyPart::Chest: return "chest";
    case BodyPart::Head: return "head";
    case BodyPart::LeftArm:
      return "left_arm";
    case BodyPart::RightArm:
      return "right_arm";
  }
  return "?";
}

}  // namespace mgrl
