// One behaviour's problem as episodes (episodes.hpp).
#include "mgrl/session/episodes.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl {

Episodes::Episodes(const StateActionModel& model, const Behavior& behavior, std::size_t count,
                   const EpisodeOptions& options)
    : model_(model), behavior_(behavior), options_(options) {
  if (count < 1 || count > 1'000'000)
    throw Error(fmt::format("num_envs: expected a number of environments in [1, 1000000], found {}", count));
  if (!(options.seconds > 0 && options.seconds <= 3600))
    throw Error(fmt::format("max_seconds: expected seconds of motion per episode in (0, 3600], found {}", options.seconds));
  frameLimit_ = options.seconds / model.frameTime;
  for (std::size_t s = 0; s < model.stateCount(); ++s)
    maxActions_ = std::max<std::size_t>(maxActions_, model.stateActionBegin[s + 1] - model.stateActionBegin[s]);
  dimension_ = behavior.discretizer->dimension();
  opponent_ = behavior.environment->as<TrackedOpponent>();
  slots_.resize(count);
  for (std::size_t i = 0; i < count; ++i) {
    slots_[i].rng = Rng(i + 1);
    start(slots_[i]);
  }
}

// As Q-learning restarts its walk: a state uniformly, a target uniform in the grid's
// coordinates until one falls inside; a moving target's motion drawn after its place. What
// the caller placed replaces what was drawn, and the target's motion is then drawn at the
// placed position (an opponent's facing depends on it).
void Episodes::start(Slot& slot, const EpisodeStart& at) {
  const Discretizer& grid = *behavior_.discretizer;
  slot.state = static_cast<std::uint32_t>(slot.rng.below(model_.stateCount()));
  if (at.state) slot.state = static_cast<std::uint32_t>(*at.state);
  TargetState e;
  do e = grid.sample(slot.rng);
  while (!grid.inside(e));
  if (at.target) e.position = *at.target;
  slot.target = e.moving() ? e : behavior_.environment->draw(e.position, slot.rng);
  slot.frames = 0;
  slot.trackers.clear();
  if (behavior_.success) slot.trackers.emplace_back(*behavior_.success, model_.frameTime);
}

void Episodes::reset(std::size_t i, std::optional<std::uint64_t> seed, const EpisodeStart& at) {
  const std::size_t states = model_.stateCount();
  if (at.state && (*at.state < 0 || static_cast<std::uint64_t>(*at.state) >= states))
    throw Error(fmt::format("options['state']: expected a graph state in [0, {}), found {}", states, *at.state));
  if (at.target && !at.target->allFinite())
    throw Error(
        fmt::format("options['target']: expected a finite position (x, y, z in metres, the avatar's frame), "
                    "found ({}, {}, {})",
                    at.target->x(), at.target->y(), at.target->z()));
  Slot& slot = slots_[i];
  if (seed) slot.rng = Rng(*seed);
  start(slot, at);
}

EpisodeStep Episodes::step(std::size_t i, std::size_t choice) {
  Slot& slot = slots_[i];
  const std::size_t n = actionsAt(i);
  if (choice >= n)
    throw Error(fmt::format("action: expected an index into state {}'s {} out-actions (info['action_mask']), found {}",
                            slot.state, n, choice));
  const std::size_t a = model_.stateActionBegin[slot.state] + choice;
  EpisodeStep out;
  out.reward = static_cast<float>(behavior_.reward->evaluate(model_, a, slot.target));
  for (SuccessCriterion::Tracker& tracker : slot.trackers)
    out.success |= tracker.play(model_, a, slot.target, opponent_) > 0;
  slot.target = behavior_.environment->next(model_, a, slot.target);
  slot.state = model_.actionTo[a];
  slot.frames += model_.actionLength(a);
  out.terminated = !behavior_.discretizer->inside(slot.target) || (options_.endOnSuccess && out.success);
  out.truncated = !out.terminated && static_cast<double>(slot.frames) >= frameLimit_;
  return out;
}

void Episodes::stepAll(const std::int64_t* choices, EpisodeStep* out, EpisodeEnd* ends) {
  for (std::size_t i = 0; i < slots_.size(); ++i)
    if (choices[i] < 0 || static_cast<std::size_t>(choices[i]) >= actionsAt(i))
      throw Error(fmt::format("actions[{}]: expected an index into state {}'s {} out-actions (info['action_mask'][{}]), "
                              "found {}",
                              i, slots_[i].state, actionsAt(i), i, choices[i]));
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    out[i] = step(i, static_cast<std::size_t>(choices[i]));
    if (!out[i].terminated && !out[i].truncated) continue;
    if (ends) observe(i, &ends[i].state, ends[i].position, ends[i].coordinates, nullptr);
    start(slots_[i]);
  }
}

void Episodes::observe(std::size_t i, std::int32_t* state, float* position, float* coordinates,
                       std::uint8_t* mask) const {
  const Slot& slot = slots_[i];
  if (state) *state = static_cast<std::int32_t>(slot.state);
  if (position)
    for (int k = 0; k < 3; ++k) position[k] = static_cast<float>(slot.target.position[k]);
  if (coordinates) {
    const std::array<double, 3> c = behavior_.discretizer->coordinates(slot.target);
    for (int k = 0; k < dimension_; ++k) coordinates[k] = static_cast<float>(c[static_cast<std::size_t>(k)]);
  }
  if (mask) {
    const std::size_t n = actionsAt(i);
    std::fill(mask, mask + n, std::uint8_t{1});
    std::fill(mask + n, mask + maxActions_, std::uint8_t{0});
  }
}

}  // namespace mgrl
