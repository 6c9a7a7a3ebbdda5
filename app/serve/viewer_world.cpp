// A page's world: built at once or on a worker thread (ViewerSession::rebuild), then
// installed with the page's controller, trackers and first frame. Apart from
// viewer.cpp, which handles the messages and steps the world.
#include <sys/resource.h>
#include <unistd.h>

#include <atomic>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "serve/viewer_parts.hpp"

namespace mgrl::serve {

using json = nlohmann::json;

namespace {

// One world is built in the background at a time on the whole server (the others' changes
// of mode wait): the builds share the cores with the network thread.
std::atomic<bool> gBuilding{false};

}  // namespace

void ViewerSession::rebuild(Mode mode, int avatars) {
  // Sparring and crowds may play another scenario's behaviours (ViewerAssets::sparring).
  std::shared_ptr<const ViewerAssets> want = mode != Mode::Target && root_->sparring ? root_->sparring : root_;
  WorldSetup setup =
      want->session->worldSetup(static_cast<std::size_t>(avatars), 1, {"random"}, want->played);  // replaced below
  setup.params.mode = mode == Mode::Target ? "targets" : "sparring";
  setup.threads = 1;  // every page on the server's one thread
  setup.poses = true;
  setup.sourcePoses = want->sourcePoses;
  bool idle = false;
  if (!background_ || !gBuilding.compare_exchange_strong(idle, true)) {
    install(std::make_unique<World>(std::move(setup)), mode, std::move(want));
    return;
  }
  // The first frame, where every avatar decides at once (a third of a second for a crowd of
  // 2,000 playing a sparring scenario's policies), runs here too, with the controller the
  // page's choices will make once the world is installed (its messages wait until then).
  const PageController first = pageController(*want, choicesAfterAdopting(*want), static_cast<std::size_t>(avatars));
  const ControllerRegistry* registry = &controllers();
  setup.makeController = [first, registry]() { return makeController(*registry, first.choice, first.parts); };
  auto build = std::make_shared<State::Build>();
  build->mode = mode;
  build->assets = std::move(want);
  startWorker([build, setup = std::move(setup)]() mutable {
    // Below the network thread: the pages' frames and requests come first.
    setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), 19);
    try {
      auto world = std::make_unique<World>(std::move(setup));
      world->run(1);
      build->world = std::move(world);
    } catch (const std::exception& e) {
      build->failure = e.what();
    }
    gBuilding = false;
    build->done = true;
  });
  state_->build = std::move(build);
}

bool ViewerSession::ready(std::string_view text) const {
  if (state_->build) return false;
  if (!background_ || !gBuilding) return true;
  try {
    return !std::holds_alternative<SetMode>(parseClientMessage(text, controllers().names()));
  } catch (const Error&) {
    return true;  // refused at once
  }
}

bool ViewerSession::poll() {
  State& s = *state_;
  if (!s.build || !s.build->done) return false;
  const std::shared_ptr<State::Build> build = std::move(s.build);
  if (!build->failure.empty()) {
    outbox_.push_back(json{{"type", "error"}, {"message", fmt::format("mode: {}", build->failure)}}.dump());
    return true;
  }
  install(std::move(build->world), build->mode, build->assets, true);
  return true;
}

void ViewerSession::install(std::unique_ptr<World> world, Mode mode, std::shared_ptr<const ViewerAssets> assets,
                            bool started) {
  if (assets != assets_) adopt(std::move(assets));
  const ViewerAssets& a = *assets_;
  State& s = *state_;
  s.world = std::move(world);
  mode_ = mode;
  s.adjustment.clear();
  applyController();
  s.carry = 0;
  s.eventsSeen = 0;
  s.hitTimes.clear();
  s.trackers.assign(s.world->avatarCount(), {});
  for (auto& list : s.trackers)
    for (const SuccessCriterion& c : a.criteria) list.emplace_back(c, a.model().frameTime);
  s.decisionsFollowed.assign(s.world->avatarCount(), 0);
  s.successes = 0;
  s.successTimes.clear();
  s.decisions = {};
  s.valuesFrame = 0;  // the new world counts frames from 0
  s.valuesSent.clear();
  if (!started) s.world->run(1);  // poses exist from the first frame on
  outbox_.push_back(scene());
}

}  // namespace mgrl::serve
