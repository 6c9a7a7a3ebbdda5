// q_learning's checkpoint state (q_learning_checkpoint.hpp): written with the table at each
// checkpoint, read back strictly on --resume.
#include "q_learning_checkpoint.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mgrl/core/error.hpp"

namespace mgrl::learners {

// `capped`: the episode length is limited, so it is part of the state (absent otherwise,
// so that checkpoints of the paper's rule keep their format).
nlohmann::json toJson(const Walk& w, bool capped) {
  nlohmann::json rng = nlohmann::json::array();
  for (std::uint64_t word : w.rng.state()) rng.push_back(word);
  nlohmann::json j = {{"updates", w.updates},
                      {"restarts", w.restarts},
                      {"state", w.state},
                      {"target", {w.target.position.x(), w.target.position.y(), w.target.position.z()}},
                      {"rng", rng}};
  if (capped) j["episode_actions"] = w.episodeActions;
  // A moving target's speed and heading, and its turn rate if it turns; absent for static
  // targets (their format unchanged).
  if (w.target.moving() || w.target.heading != 0 || w.target.turnRate != 0) {
    j["target_motion"] = {w.target.speed, w.target.heading};
    if (w.target.turnRate != 0) j["target_motion"].push_back(w.target.turnRate);
  }
  return j;
}

// The grid cells the walk has been in, for the coverage report, as hex digits: digit i
// holds cells 4i to 4i + 3, the lowest bit first. A checkpoint keeps them so a resumed run
// reports the coverage of the whole walk, as an uninterrupted one does (the kill
// tests found a resumed run reporting only the cells walked after the resume).
std::string encodeCells(const std::vector<std::uint8_t>& seen) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string text((seen.size() + 3) / 4, '0');
  for (std::size_t i = 0; i < text.size(); ++i) {
    unsigned digit = 0;
    for (std::size_t bit = 0; bit < 4 && 4 * i + bit < seen.size(); ++bit)
      digit |= (seen[4 * i + bit] ? 1u : 0u) << bit;
    text[i] = kDigits[digit];
  }
  return text;
}

nlohmann::json savedState(const Walk& w, bool capped, double seconds, const std::vector<CurvePoint>& curve,
                          const std::vector<std::uint8_t>& cellSeen) {
  nlohmann::json points = nlohmann::json::array();
  for (const CurvePoint& p : curve) points.push_back({p.updates, p.seconds, p.residual, p.meanResidual});
  return {{"updates", w.updates},
          {"walk", toJson(w, capped)},
          {"seconds", seconds},
          {"curve", points},
          {"cells_seen", encodeCells(cellSeen)}};
}

// The inverse of savedState(), read through `r` (which names the file) at path
// "state". Throws mgrl::Error naming the member, what was expected and what was found.
Saved readSaved(const nlohmann::json& state, const ManifestReader& r, std::size_t states, std::size_t cells,
                std::uint64_t budget, std::uint64_t curvePoints, std::uint64_t maxEpisode) {
  using nlohmann::json;
  if (!state.is_object()) r.fail("state", "an object", state);
  for (const auto& item : state.items())
    if (item.key() != "updates" && item.key() != "walk" && item.key() != "seconds" && item.key() != "curve" &&
        item.key() != "cells_seen")
      r.fail("state", "only the keys updates, walk, seconds, curve, cells_seen", json(item.key()));
  Saved saved;
  Walk& w = saved.walk;
  // target_motion is optional (a moving target's speed and heading; absent for static ones).
  const json& walk =
      maxEpisode > 0
          ? r.object(state, "state", "walk",
                     {"updates", "restarts", "state", "target", "rng", "episode_actions", "target_motion"})
          : r.object(state, "state", "walk", {"updates", "restarts", "state", "target", "rng", "target_motion"});
  if (maxEpisode > 0) w.episodeActions = r.unsignedInteger(walk, "state.walk", "episode_actions", maxEpisode - 1);
  w.updates = r.unsignedInteger(walk, "state.walk", "updates", budget);
  if (r.unsignedInteger(state, "state", "updates", budget) != w.updates)
    r.fail("state.updates", fmt::format("{}, as state.walk.updates", w.updates), state["updates"]);
  w.restarts = r.unsignedInteger(walk, "state.walk", "restarts", std::numeric_limits<std::uint64_t>::max());
  w.state = static_cast<std::uint32_t>(r.unsignedInteger(walk, "state.walk", "state", states - 1));
  const json& target = r.member(walk, "state.walk", "target");
  if (!target.is_array() || target.size() != 3 || !std::all_of(target.begin(), target.end(), [](const json& v) {
        return v.is_number() && std::isfinite(v.get<double>());
      }))
    r.fail("state.walk.target", "3 finite numbers", target);
  w.target = TargetState(target[0].get<double>(), target[1].get<double>(), target[2].get<double>());
  if (walk.contains("target_motion")) {
    const json& motion = walk["target_motion"];
    if (!motion.is_array() || motion.size() < 2 || motion.size() > 3 ||
        !std::all_of(motion.begin(), motion.end(),
                     [](const json& v) { return v.is_number() && std::isfinite(v.get<double>()); }) ||
        motion[0].get<double>() < 0)
      r.fail("state.walk.target_motion",
             "2 or 3 finite numbers: a speed >= 0 (m/s), a heading (rad) and a turn rate (rad/s)", motion);
    w.target.speed = motion[0].get<double>();
    w.target.heading = motion[1].get<double>();
    if (motion.size() == 3) w.target.turnRate = motion[2].get<double>();
  }
  const json& rng = r.member(walk, "state.walk", "rng");
  if (!rng.is_array() || rng.size() != 4 ||
      !std::all_of(rng.begin(), rng.end(), [](const json& v) { return v.is_number_unsigned(); }))
    r.fail("state.walk.rng", "4 integers in [0, 18446744073709551615]", rng);
  std::array<std::uint64_t, 4> words{};
  for (int i = 0; i < 4; ++i) words[i] = rng[i].get<std::uint64_t>();
  // xoshiro's one fixed point: it would return 0 forever.
  if (words == std::array<std::uint64_t, 4>{}) r.fail("state.walk.rng", "a generator state other than all zeros", rng);
  w.rng.setState(words);

  saved.seconds = r.number(state, "state", "seconds");
  if (!(saved.seconds >= 0) || !std::isfinite(saved.seconds))
    r.fail("state.seconds", "a finite number of seconds of at least 0", state["seconds"]);
  const json& curve = r.member(state, "state", "curve");
  if (!curve.is_array() || curve.size() > curvePoints)
    r.fail("state.curve", fmt::format("an array of at most {} points", curvePoints), curve);
  for (std::size_t i = 0; i < curve.size(); ++i) {
    const json& p = curve[i];
    const std::string path = fmt::format("state.curve[{}]", i);
    const std::uint64_t after = saved.curve.empty() ? 0 : saved.curve.back().updates;
    if (!p.is_array() || p.size() != 4 || !p[0].is_number_unsigned() ||
        !std::all_of(p.begin() + 1, p.end(),
                     [](const json& v) { return v.is_number() && std::isfinite(v.get<double>()); }))
      r.fail(path, "[updates, seconds, residual, mean residual], all finite numbers", p);
    const std::uint64_t updates = p[0].get<std::uint64_t>();
    if (updates <= after || updates > w.updates)
      r.fail(path + "[0]",
             fmt::format("an update count in [{}, {}] (after the previous point, not past the walk)", after + 1,
                         w.updates),
             p[0]);
    saved.curve.push_back({updates, p[1].get<double>(), p[2].get<double>(), p[3].get<double>()});
  }
  const std::string seen = r.string(state, "state", "cells_seen");
  const std::size_t digits = (cells + 3) / 4;
  // The last digit holds only the cells there are: its unused bits must be 0.
  const unsigned lastMask = cells % 4 == 0 ? 0xfu : (1u << (cells % 4)) - 1;
  auto value = [](char c) { return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1; };
  if (seen.size() != digits || !std::all_of(seen.begin(), seen.end(), [&](char c) { return value(c) >= 0; }) ||
      (digits > 0 && (static_cast<unsigned>(value(seen.back())) & ~lastMask) != 0))
    r.fail("state.cells_seen", fmt::format("{} lowercase hex digits, one bit per grid cell of {}", digits, cells),
           json(seen.substr(0, 32)));
  saved.cellSeen.assign(cells, 0);
  for (std::size_t c = 0; c < cells; ++c) saved.cellSeen[c] = (value(seen[c / 4]) >> (c % 4)) & 1;
  return saved;
}

}  // namespace mgrl::learners
