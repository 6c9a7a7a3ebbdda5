#pragma once
/// \file
/// What a `q_learning` checkpoint holds beside the table (training that survives a kill):
/// the walk that determines the rest of a run, its writing, and its reading back, strict in
/// every member.
/// Split from q_learning.cpp, which runs the walk: this file changes when the format does.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "mgrl/core/bundle.hpp"
#include "mgrl/core/random.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/learning/target_state.hpp"

namespace mgrl::learners {

// Everything that determines the rest of a run, so a checkpoint resumes it exactly.
struct Walk {
  Rng rng;
  std::uint64_t updates = 0, restarts = 0;
  std::uint64_t episodeActions = 0;  ///< actions since the last restart (for max_episode_actions)
  std::uint32_t state = 0;
  TargetState target;
};

// What a checkpoint holds beside the table. A resumed run trusts all of it, so every
// member is read strictly: a bad one rejects the checkpoint (see StateCheck).
struct Saved {
  Walk walk;
  double seconds = 0;
  std::vector<CurvePoint> curve;
  std::vector<std::uint8_t> cellSeen;
};

/// The walk as a checkpoint's "walk" member. `capped`: the episode length is limited, so it
/// is part of the state (absent otherwise, so that checkpoints of the paper's rule keep
/// their format).
nlohmann::json toJson(const Walk& w, bool capped);

/// The grid cells the walk has been in, as hex digits (digit i: cells 4i to 4i + 3, the
/// lowest bit first).
std::string encodeCells(const std::vector<std::uint8_t>& seen);

/// The state train() saves beside the table: the walk's update count, the walk
/// (toJson(w, capped)), the training seconds so far, the learning curve and the cells seen
/// (encodeCells()).
nlohmann::json savedState(const Walk& w, bool capped, double seconds, const std::vector<CurvePoint>& curve,
                          const std::vector<std::uint8_t>& cellSeen);

/// The inverse of savedState(), read through `r` (which names the file) at path
/// "state". Throws mgrl::Error naming the member, what was expected and what was found.
Saved readSaved(const nlohmann::json& state, const ManifestReader& r, std::size_t states, std::size_t cells,
                std::uint64_t budget, std::uint64_t curvePoints, std::uint64_t maxEpisode);

}  // namespace mgrl::learners
