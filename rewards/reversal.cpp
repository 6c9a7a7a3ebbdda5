// term: reversal (a cost): 1 at each frame whose root step, faster than min_speed_mps,
// points against the direction the avatar last travelled in, as `mgrl stats` counts a
// root reversal (framework/runtime/bout_stats.cpp): restless feet that step in and out
// every action.
//
// The direction at an action's first frame is the one the avatar arrives at its state with:
// the last fast step of an action ending there along its own clip (the capture's own
// motion into the state's frame), else of any action ending there. Steps inside the action
// then carry it on. A function of the action alone, tabulated once at bind().
#include <cmath>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Core>

#include "term.hpp"

namespace mgrl::rewards {

namespace {

// Step t (1-based) of action a in the decision's avatar frame (ground x, z).
Eigen::Vector2d stepOf(const StateActionModel& m, std::size_t a, std::size_t t) {
  const std::size_t frame = m.actionFrameBegin[a] + t - 1;
  const double* r = &m.frameRoot[3 * frame];
  return t > 1 ? Eigen::Vector2d(r[0] - r[-3], r[1] - r[-2]) : Eigen::Vector2d(r[0], r[1]);
}

// The last step of action a faster than `minStep` (m a frame), turned into the avatar frame
// at its end (the decision frame of the actions leaving its end state); none if it has none.
std::optional<Eigen::Vector2d> arrivingDirection(const StateActionModel& m, std::size_t a, double minStep) {
  const std::size_t length = m.actionLength(a);
  const double endYaw = m.frameRoot[3 * (m.actionFrameBegin[a] + length - 1) + 2];
  for (std::size_t t = length; t >= 1; --t) {
    const Eigen::Vector2d step = stepOf(m, a, t);
    if (step.norm() < minStep) continue;
    // A ground vector (x, z) seen from a frame turned by yaw about +Y (ground_motion.hpp).
    const double c = std::cos(endYaw), s = std::sin(endYaw);
    return Eigen::Vector2d(c * step.x() - s * step.y(), s * step.x() + c * step.y());
  }
  return std::nullopt;
}

class Reversal final : public Term {
 public:
  explicit Reversal(const Params& p) : minSpeed_(p.number("min_speed_mps")) {}

  void bind(const StateActionModel& m) override {
    const double minStep = minSpeed_ * m.frameTime;
    // The direction each state is arrived at with: an action along its clip first.
    std::vector<std::optional<Eigen::Vector2d>> arriving(m.stateCount());
    std::vector<std::uint8_t> alongClip(m.stateCount(), 0);
    for (std::size_t a = 0; a < m.actionCount(); ++a) {
      const std::uint32_t s = m.actionTo[a];
      const std::size_t last = m.actionFrameBegin[a] + m.actionLength(a) - 1;
      const bool along = m.actionLength(a) >= 2 && m.actionFrames[last - 1] + 1 == m.actionFrames[last];
      if (alongClip[s] || (arriving[s] && !along)) continue;
      if (std::optional<Eigen::Vector2d> d = arrivingDirection(m, a, minStep)) {
        arriving[s] = d;
        alongClip[s] = along;
      }
    }
    reversed_.assign(m.actionFrames.size(), 0);
    for (std::size_t a = 0; a < m.actionCount(); ++a) {
      std::optional<Eigen::Vector2d> direction = arriving[m.actionFrom[a]];
      for (std::size_t t = 1; t <= m.actionLength(a); ++t) {
        const Eigen::Vector2d step = stepOf(m, a, t);
        if (step.norm() < minStep || step.norm() == 0) continue;
        if (direction && step.dot(*direction) < 0) reversed_[m.actionFrameBegin[a] + t - 1] = 1;
        direction = step;
      }
    }
  }
  double signal(const TermFrame& f) const override {
    // Tabulated for the bound model's action frames: another model's would read past them.
    if (reversed_.size() != f.model.actionFrames.size())
      throw std::logic_error("reward term reversal evaluated on a model it was not bound to");
    return reversed_[f.frame];
  }
  bool cost() const override { return true; }

 private:
  double minSpeed_;
  std::vector<std::uint8_t> reversed_;  ///< 1 per action frame that reverses
};

}  // namespace

void registerReversal(Vocabulary& v) {
  v.terms.add({"reversal",
               "a cost: 1 at each frame whose root step (faster than min_speed_mps) points against the direction the "
               "avatar last travelled in, the one it arrived at the state with included",
               {ParamSpec::number("min_speed_mps", 0.2, 0, 10, "m/s",
                                  "slower root steps neither count nor change the direction (mgrl stats' "
                                  "--reversal-min-speed)"),
                weightSpec()},
               [](const Params& p) { return std::make_unique<Reversal>(p); }});
}

}  // namespace mgrl::rewards
