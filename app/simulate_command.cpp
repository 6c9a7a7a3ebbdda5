// `mgrl simulate` (DESIGN.md sec. 5): the world run headless (paper sec. 5, 6.6, 6.7):
// avatars in sparring pairs or with targets, controlled by the trained policy (or the
// online search, or at random), collisions at effective punches, reactions. Reports speed
// and hits; writes one BVH per avatar and the hits as JSON lines, atomically
// (mgrl/session/exports.hpp).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <fmt/format.h>

#include "learn_commands.hpp"
#include "mgrl/core/bundle.hpp"
#include "mgrl/core/files.hpp"
#include "mgrl/core/hash.hpp"
#include "mgrl/core/numbers.hpp"
#include "mgrl/core/parallel.hpp"
#include "mgrl/core/version.hpp"
#include "mgrl/learning/behavior.hpp"
#include "mgrl/learning/policy_bundle.hpp"
#include "mgrl/motion/bvh.hpp"
#include "mgrl/motion/gltf.hpp"
#include "mgrl/motion/motion_io.hpp"
#include "mgrl/runtime/controller.hpp"
#include "mgrl/runtime/world.hpp"
#include "mgrl/scenario/behaviors.hpp"
#include "mgrl/session/session.hpp"
#include "mgrl/session/simulate.hpp"
#include "plugins.hpp"
#include "plural.hpp"
#include "startup.hpp"

namespace mgrl::app {

namespace fs = std::filesystem;
using json = nlohmann::json;

json runSimulate(const SimulateOptions& options) {
  SimulateSettings settings = options.run;
  settings.log = options.log;
  settings.startup = secondsSinceStart;
  const ControllerRegistry& controllers = requirePlugins(options.plugins, "SessionOptions::plugins").controllers;
  checkSimulateSettings(controllers, settings);
  Outputs out;
  SessionNeeds needs;
  needs.policy = controllers.find(settings.controller.name)->needsPolicy ? PolicyNeed::Required : PolicyNeed::None;
  needs.policyDir = options.policy;
  needs.beforeGraph = [&](const Scenario& scenario) { out = prepareOutputs(settings.exportRequest(), scenario); };
  const std::unique_ptr<const Session> session = openSession(options, needs);
  return simulate(*session, settings, out);
}

std::string simulateText(const json& r) {
  std::string text = fmt::format(
      "simulate ({} controller, {}): {} x {} ({:.1f} s) in {}: {}avatar-frames/s\n"
      "hits: {} ({:.1f} per avatar-minute; head {}, chest {}, spine {}, targets {}); blocked {}\n",
      r["controller"].get<std::string>(), r["mode"].get<std::string>(),
      counted(r["avatars"].get<std::size_t>(), "avatar"), counted(r["frames"].get<std::size_t>(), "frame"),
      r["seconds"].get<double>(), humanSeconds(r["wall_seconds"].get<double>()),
      humanCount(r["avatar_frames_per_second"].get<double>()), r["hits"].get<std::size_t>(),
      r["hits_per_avatar_minute"].get<double>(), r["hits_by_part"]["head"].get<std::size_t>(),
      r["hits_by_part"]["chest"].get<std::size_t>(), r["hits_by_part"]["spine"].get<std::size_t>(),
      r["hits_by_part"]["target"].get<std::size_t>(), r["blocked"].get<std::size_t>());
  if (r.contains("partner"))
    text += fmt::format("sides: the avatars landed {}, their scripted opponents ({}) landed {}\n",
                        r["hits_by_side"]["avatars"].get<std::size_t>(), r["partner"].get<std::string>(),
                        r["hits_by_side"]["opponents"].get<std::size_t>());
  else if (r.contains("hits_by_side"))
    text += fmt::format("sides: {} landed {}, {} (the partners) landed {}\n", r["policy"].get<std::string>(),
                        r["hits_by_side"]["policy"].get<std::size_t>(), r["partner_policy"].get<std::string>(),
                        r["hits_by_side"]["partner_policy"].get<std::size_t>());
  if (r.contains("bvh_files"))
    text += fmt::format("wrote {} to {}\n", counted(r["bvh_files"].size(), "BVH file"),
                        r["bvh_folder"].get<std::string>());
  if (r.contains("gltf_files"))
    text += fmt::format("wrote {} to {}\n", counted(r["gltf_files"].size(), "glTF file"),
                        r["gltf_folder"].get<std::string>());
  if (r.contains("events_file")) text += fmt::format("wrote the hits to {}\n", r["events_file"].get<std::string>());
  return text;
}

}  // namespace mgrl::app
