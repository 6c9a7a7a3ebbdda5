// mgrl serve (docs/viewer-protocol.md): the page's messages, the pose frame, static files,
// a page's world, and the real server over real sockets with hostile pages beside a good one.
#include <chrono>
#include <fstream>
#include <thread>
#include <utility>  // before Boost 1.74's asio, which uses std::exchange without it

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <catch2/catch.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "learn_commands.hpp"
#include "mgrl/core/files.hpp"
#include "serve/protocol.hpp"
#include "serve/serve_command.hpp"
#include "serve/server.hpp"
#include "serve/static_files.hpp"
#include "serve/viewer.hpp"
#include "serve/viewer_parts.hpp"
#include "serve_support.hpp"
#include "test_support.hpp"

namespace mgrl::serve_test {
namespace {

// fs, beast, http, websocket, net, tcp and json come with the helpers' namespace.
using namespace test::serving;

// A page message as `mgrl serve` parses it: its controllers are the built-in ones.
serve::ClientMessage parseClientMessage(std::string_view text) {
  return serve::parseClientMessage(text, builtinPlugins().controllers.names());
}

// The median ground distance between avatars 0's and 1's pelvises over `seconds` of the
// page's world (after its first 2 s, from the start's spacing); counts `values` messages.
double medianPelvisDistance(serve::ViewerSession& page, double seconds, int* valuesMessages) {
  std::vector<double> d;
  for (int f = 0; f < static_cast<int>(seconds / page.frameTime()); ++f) {
    page.advance(1.0);
    for (const std::string& m : page.takeOutbox())
      if (valuesMessages && json::parse(m)["type"] == "values") ++*valuesMessages;
    const serve::DecodedFrame frame = serve::decodeFrame(page.frame());
    if (f * page.frameTime() < 2) continue;
    const Eigen::Vector3d a = frame.avatars.at(0).at(0), b = frame.avatars.at(1).at(0);
    d.push_back(std::hypot(a.x() - b.x(), a.z() - b.z()));
  }
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

TEST_CASE("page messages are taken only when every field is what the protocol says", "[serve]") {
  const auto mode = std::get<serve::SetMode>(parseClientMessage(R"({"type": "mode", "mode": "crowd", "avatars": 100})"));
  CHECK(mode.mode == serve::Mode::Crowd);
  CHECK(mode.avatars == 100);
  CHECK(std::get<serve::SetMode>(parseClientMessage(R"({"type": "mode", "mode": "crowd"})")).avatars == 30);
  CHECK(std::get<serve::SetMode>(parseClientMessage(R"({"type": "mode", "mode": "sparring"})")).avatars == 2);
  const auto move = std::get<serve::MoveTarget>(parseClientMessage(R"({"type": "move_target", "position": [1.5, 1.2, -0.5]})"));
  CHECK(move.position.isApprox(Eigen::Vector3d(1.5, 1.2, -0.5)));
  const auto controller =
      std::get<serve::SetController>(parseClientMessage(R"({"type": "controller", "controller": "online_search", "horizon": 2})"));
  CHECK(controller.controller == "online_search");
  CHECK(controller.horizon == 2);
  CHECK(std::get<serve::SetWeights>(parseClientMessage(R"({"type": "weights", "weights": {"hit": 2.5}})")).weights.at("hit") == 2.5);
  CHECK(std::get<serve::Pause>(parseClientMessage(R"({"type": "pause", "paused": true})")).paused);
  CHECK(std::holds_alternative<serve::Step>(parseClientMessage(R"({"type": "step"})")));
  CHECK(std::get<serve::SetSpeed>(parseClientMessage(R"({"type": "speed", "speed": 0.5})")).speed == 0.5);
  const auto start = std::get<serve::Learn>(
      parseClientMessage(R"({"type": "learn", "command": "start", "behavior": "hit", "seed": 4, "budget": 500})"));
  CHECK((start.command == serve::Learn::Command::Start && start.behavior == "hit" && start.seed == 4 && start.budget == 500));
  CHECK(std::get<serve::Learn>(parseClientMessage(R"({"type": "learn", "command": "step", "steps": 10})")).steps == 10);
  CHECK(std::get<serve::Learn>(parseClientMessage(R"({"type": "learn", "command": "run", "rate": 50})")).rate == 50);
  const auto retrain = std::get<serve::Retrain>(
      parseClientMessage(R"({"type": "retrain", "behavior": "hit", "set": {"reward.contact_radius": 0.2, "discretizer.angles": 12}})"));
  CHECK((retrain.behavior == "hit" && retrain.set.at("reward.contact_radius") == 0.2 && retrain.set.at("discretizer.angles") == 12));

  const std::vector<std::pair<std::string, std::string>> refused = {
      {"not json", "expected a JSON object, found text that is not JSON"},
      {"[1, 2]", "expected a JSON object, found [1,2]"},
      {R"({"mode": "target"})", "expected a field \"type\""},
      {R"({"type": 7})", "message.type: expected a string, found 7"},
      {R"({"type": "explode"})", "expected one of mode, move_target, controller, weights, pause, step, speed, values, learn, retrain, found \"explode\""},
      {R"({"type": "learn"})", "learn: expected a field \"command\""},
      {R"({"type": "learn", "command": "teach"})", "learn.command: expected one of start, step, run, stop, found \"teach\""},
      {R"({"type": "learn", "command": "start"})", "learn: expected a field \"behavior\""},
      {R"({"type": "learn", "command": "start", "behavior": "hit", "budget": 0})", "learn.budget: expected a whole number in [1, 10000000], found 0"},
      {R"({"type": "learn", "command": "start", "behavior": "hit", "seed": -1})", "learn.seed: expected a whole number in [0, 2147483647], found -1"},
      {R"({"type": "learn", "command": "step", "steps": 1001})", "learn.steps: expected a whole number in [1, 1000], found 1001"},
      {R"({"type": "learn", "command": "step", "behavior": "hit"})", "learn: unexpected field \"behavior\""},
      {R"({"type": "learn", "command": "run", "rate": 1e9})", "learn.rate: expected a number in [0, 2000], found 1000000000"},
      {R"({"type": "retrain", "behavior": "hit"})", "retrain: expected a field \"set\""},
      {R"({"type": "retrain", "behavior": "hit", "set": [1]})", "retrain.set: expected an object of at most 8 parameters"},
      {R"({"type": "retrain", "behavior": "hit", "set": {"learner.budget": 5}})", "expected parameters named reward.NAME or discretizer.NAME, found \"learner.budget\""},
      {R"({"type": "retrain", "behavior": "hit", "set": {"reward.": 5}})", "found \"reward.\""},
      {R"({"type": "retrain", "behavior": "hit", "set": {"reward.a.b": 5}})", "found \"reward.a.b\""},
      {R"({"type": "retrain", "behavior": "hit", "set": {"reward.sigma": "wide"}})", "retrain.set[\"reward.sigma\"]: expected a number"},
      {R"({"type": "step", "extra": 1})", "step: unexpected field \"extra\""},
      {R"({"type": "mode", "mode": "dance"})", "mode.mode: expected one of target, sparring, crowd, found \"dance\""},
      {R"({"type": "mode", "mode": "crowd", "avatars": 2001})", "mode.avatars: expected a whole number in [2, 2000], found 2001"},
      {R"({"type": "mode", "mode": "crowd", "avatars": 2.5})", "mode.avatars: expected a whole number in [2, 2000], found 2.5"},
      {R"({"type": "mode", "mode": "sparring", "avatars": 4})", "\"avatars\" is only for the crowd"},
      {R"({"type": "move_target", "position": [1, 2]})", "move_target.position: expected [x, y, z] in metres"},
      {R"({"type": "move_target", "position": [1, 9, 0]})", "move_target.position[1]: expected a number in [0, 3], found 9"},
      {R"({"type": "move_target", "position": [1e300, 1, 0]})", "move_target.position[0]: expected a number in [-100, 100]"},
      {R"({"type": "move_target", "position": ["1", 1, 0]})", "move_target.position[0]: expected a number"},
      {R"({"type": "controller", "controller": "magic"})", "controller.controller: expected one of policy, online_search, random"},
      {R"({"type": "controller", "controller": "random", "horizon": 9})", "controller.horizon: expected a whole number in [1, 5], found 9"},
      {R"({"type": "weights", "weights": {"hit": -1}})", "weights.weights[\"hit\"]: expected a number in [0, 10], found -1"},
      {R"({"type": "weights", "weights": []})", "weights.weights: expected an object of behaviour names and weights"},
      {R"({"type": "pause", "paused": "yes"})", "pause.paused: expected true or false, found \"yes\""},
      {R"({"type": "speed"})", "speed: expected a field \"speed\", found none"},
      {R"({"type": "speed", "speed": 100})", "speed.speed: expected a number in [0.1, 4], found 100"},
      {std::string(5000, ' '), "message: expected at most 4096 bytes, found 5000"},
  };
  for (const auto& [text, message] : refused) {
    INFO(text.substr(0, 80));
    REQUIRE_THROWS_WITH(parseClientMessage(text), Catch::Contains(message));
  }
}

TEST_CASE("a pose frame carries every joint within half a millimetre and its sizes add up", "[serve]") {
  std::vector<Eigen::Vector3d> a = {{10.0, 0.95, -3.0}, {10.1, 1.5, -3.2}, {9.7, 1.8, -2.9}};
  std::vector<Eigen::Vector3d> b = {{-4.0, 1.0, 2.0}, {-4.0, 1.6, 2.0}, {-50.0, 1.0, 2.0}};  // 46 m: clamped
  serve::FrameWriter writer;
  writer.begin({3, 2, 1, 77, 2.5f});
  writer.avatar(a);
  writer.avatar(b);
  writer.target(0, {1.0, 1.4, 0.5});
  const std::vector<std::uint8_t> bytes = writer.finish();
  CHECK(bytes.size() == serve::kFrameHeaderBytes + 2 * serve::avatarRecordBytes(3) + serve::kTargetRecordBytes);
  CHECK(std::string(bytes.begin(), bytes.begin() + 4) == "MGRF");
  const serve::DecodedFrame frame = serve::decodeFrame(bytes);
  CHECK(frame.header.frame == 77);
  CHECK(frame.header.time == 2.5f);
  for (std::size_t j = 0; j < 3; ++j) CHECK((frame.avatars[0][j] - a[j]).cwiseAbs().maxCoeff() <= 0.0005 + 1e-6);
  CHECK(frame.avatars[1][2].x() == Approx(-4.0 - 32.767));  // clamped, not wrapped around
  CHECK(frame.targets.at(0).first == 0);
  CHECK(frame.targets.at(0).second.isApprox(Eigen::Vector3d(1.0, 1.4, 0.5), 1e-6));

  serve::FrameWriter short_;
  short_.begin({3, 2, 0, 0, 0});
  short_.avatar(a);
  REQUIRE_THROWS_WITH(short_.finish(), Catch::Contains("expected 2 avatars and 0 targets, found 1 and 0"));
  REQUIRE_THROWS_WITH(short_.avatar(std::vector<Eigen::Vector3d>(2)), Catch::Contains("with 3 joints, found 2 joints"));
  std::vector<std::uint8_t> cut(bytes.begin(), bytes.end() - 1);
  REQUIRE_THROWS_WITH(serve::decodeFrame(cut), Catch::Contains("pose frame: expected"));
}

TEST_CASE("static files come only from inside the web folder", "[serve]") {
  test::TempDir temp("serve-static");
  const fs::path web = temp.path / "web";
  writeFile(web / "index.html", "<html></html>");
  writeFile(web / "js" / "app.js", "export {};");
  writeFile(temp.path / "secret.txt", "secret");
  fs::create_directory_symlink(temp.path, web / "escape");
  const fs::path root = fs::canonical(web);

  CHECK(serve::lookupStatic(root, "/").file == root / "index.html");
  CHECK(serve::lookupStatic(root, "/js/app.js?v=3").file == root / "js" / "app.js");
  CHECK(serve::lookupStatic(root, "/js//app.js").status == 200);
  CHECK(serve::lookupStatic(root, "/%6As/app.js").status == 200);  // %6A is j
  CHECK(serve::lookupStatic(root, "/missing.js").status == 404);
  CHECK(serve::lookupStatic(root, "/js").status == 404);  // a folder
  for (const char* hostile : {"/../secret.txt", "/js/../../secret.txt", "/%2e%2e/secret.txt", "/%2E%2E%2Fsecret.txt",
                              "/..%2fsecret.txt", "/escape/secret.txt", "/js/%00app.js", "/js\\..\\..\\secret.txt",
                              "/%zz", "/%2", "js/app.js", "/./index.html"}) {
    INFO(hostile);
    CHECK(serve::lookupStatic(root, hostile).status == 400);
  }
  CHECK(serve::mimeType("a.js") == "text/javascript; charset=utf-8");
  CHECK(serve::mimeType("a.html") == "text/html; charset=utf-8");
  CHECK(serve::mimeType("a.png") == "image/png");
  CHECK(serve::mimeType("a.exe") == "application/octet-stream");
}


std::vector<json> textMessages(serve::ViewerSession& session) {
  std::vector<json> out;
  for (const std::string& text : session.takeOutbox()) out.push_back(json::parse(text));
  return out;
}

TEST_CASE("a page's world: the boxer punches the target where it is dragged, weights and controllers switch live",
          "[serve][data]") {
  const BoxingAssets boxing;
  serve::ViewerSession session(boxing.assets);
  std::vector<json> out = textMessages(session);
  REQUIRE(out.size() == 1);
  const json scene = out[0];
  CHECK(scene["type"] == "scene");
  CHECK(scene["mode"] == "target");
  CHECK(scene["controller"] == "policy");
  CHECK(scene["controllers"] == json::array({"policy", "online_search", "random"}));
  CHECK(scene["note"] == "");
  CHECK(scene["joints"].size() > 20);
  CHECK(scene["partners"] == json::array({-1}));

  // Drag the target 1.5 m to the side of where the boxer stands, at chest height.
  const serve::DecodedFrame before = serve::decodeFrame(session.frame());
  const Eigen::Vector3d root = before.avatars.at(0).at(0);
  const Eigen::Vector3d spot(root.x() + 1.5, 1.3, root.z());
  session.handle(json{{"type", "move_target"}, {"position", {spot.x(), spot.y(), spot.z()}}}.dump());
  REQUIRE(textMessages(session).empty());
  const int frames15s = static_cast<int>(15 / session.frameTime());
  int hitFrame = -1;
  for (int f = 0; f < frames15s && hitFrame < 0; ++f) {
    session.advance(1.0);
    for (const json& m : textMessages(session))
      if (m["type"] == "hit" && m["target"] == -1) hitFrame = f;
  }
  INFO("the boxer did not punch the dragged target within 15 s");
  CHECK(hitFrame >= 0);
  const serve::DecodedFrame after = serve::decodeFrame(session.frame());
  CHECK((after.targets.at(0).second - spot).norm() < 0.4);  // the target (bend included) is where it was put
  CHECK((after.avatars[0][0] - spot).head<1>().norm() < (root - spot).head<1>().norm());  // the boxer went there

  // The teaching view: hit's values around the boxer at its last decision, the layer of the
  // hit grid nearest the target's height, and the path of the action it took.
  session.handle(R"({"type": "values", "behavior": "hit"})");
  out = textMessages(session);
  REQUIRE(out.size() == 1);
  const json values = out[0];
  CHECK(values["type"] == "values");
  CHECK(values["behavior"] == "hit");
  CHECK(values["points"].size() == 20 * 16);  // one layer of the 20 x 16 x 6 grid
  CHECK(values["v_max"].get<double>() > values["v_min"].get<double>());
  CHECK(values["chosen"].get<std::size_t>() < values["actions"].get<std::size_t>());
  CHECK(values["path"].size() >= 2);
  for (const json& p : values["points"]) {
    CHECK(p[1].get<double>() == Approx(values["height"].get<double>()).margin(1e-3));
    CHECK(p[4].get<std::size_t>() < values["actions"].get<std::size_t>());
  }
  // It follows the boxer: more come as the world runs, none once stopped.
  int more = 0;
  for (int f = 0; f < 30; ++f) {
    session.advance(1.0);
    for (const json& m : textMessages(session)) more += m["type"] == "values";
  }
  CHECK(more >= 4);
  session.handle(R"({"type": "values", "behavior": null})");
  for (int f = 0; f < 30; ++f) {
    session.advance(1.0);
    for (const json& m : textMessages(session)) CHECK(m["type"] != "values");
  }
  session.handle(R"({"type": "values", "behavior": "kick"})");
  CHECK(textMessages(session).at(0)["message"] == "values.behavior: expected one of approach, hit or null, found \"kick\"");

  json stats = json::parse(session.stats(5, 1));
  CHECK(stats["hits"].get<int>() >= 1);
  CHECK(stats["frames_sent"] == 5);
  CHECK(stats["decision_us"].get<double>() > 0);
  // Successes as eval counts them (hit's contact within 0.15 m, from the target each
  // decision saw): the boxer that punched the dragged target has some, at most one a decision.
  const int successes = stats["successes"].get<int>();
  CHECK(successes >= 1);
  CHECK(successes <= stats["decisions"].get<int>());
  CHECK(stats["successes_per_minute"].get<double>() > 0);
  // A target 50 m away cannot be struck: 5 s on, no more successes.
  session.handle(json{{"type", "move_target"}, {"position", {root.x() + 50, 1.3, root.z()}}}.dump());
  REQUIRE(textMessages(session).empty());
  for (int f = 0; f < static_cast<int>(5 / session.frameTime()); ++f) session.advance(1.0);
  textMessages(session);
  stats = json::parse(session.stats(0, 0));
  CHECK(stats["successes"].get<int>() == successes);
  CHECK(stats["decisions"].get<int>() > 0);
  session.handle(json{{"type", "move_target"}, {"position", {spot.x(), spot.y(), spot.z()}}}.dump());
  REQUIRE(textMessages(session).empty());

  session.handle(R"({"type": "weights", "weights": {"hit": 0}})");
  out = textMessages(session);
  REQUIRE(out.size() == 1);
  CHECK(out[0]["behaviors"][1]["weight"] == 0.0);
  session.handle(R"({"type": "weights", "weights": {"kick": 1}})");
  out = textMessages(session);
  REQUIRE(out.size() == 1);
  CHECK(out[0]["type"] == "error");
  CHECK(out[0]["message"].get<std::string>().find("expected behaviour names from approach, hit, found \"kick\"") !=
        std::string::npos);

  session.handle(R"({"type": "move_target", "position": [0, 1, 0]})");  // fine in target mode
  REQUIRE(textMessages(session).empty());
  session.handle(R"({"type": "mode", "mode": "crowd", "avatars": 100})");
  out = textMessages(session);
  REQUIRE(out.size() == 1);
  CHECK(out[0]["avatars"] == 100);
  CHECK(serve::decodeFrame(session.frame()).avatars.size() == 100);
  session.handle(R"({"type": "move_target", "position": [0, 1, 0]})");
  CHECK(textMessages(session).at(0)["message"] == "move_target: expected target mode, found crowd mode");
  // A deep search for 100 avatars would stall every page: the horizon is lowered, and said.
  session.handle(R"({"type": "controller", "controller": "online_search", "horizon": 5})");
  out = textMessages(session);
  REQUIRE(out.size() == 1);
  CHECK(out[0]["controller"] == "online_search");
  CHECK(out[0]["horizon"].get<int>() < 5);
  CHECK(out[0]["note"].get<std::string>().find("horizon was lowered from 5") != std::string::npos);
  const auto start = std::chrono::steady_clock::now();
  session.advance(1.0);
  CHECK(std::chrono::steady_clock::now() - start < std::chrono::seconds(2));

  session.handle(R"({"type": "step"})");
  CHECK(textMessages(session).at(0)["type"] == "error");
  session.handle(R"({"type": "pause", "paused": true})");
  const std::uint32_t frame = serve::decodeFrame(session.frame()).header.frame;
  CHECK_FALSE(session.advance(5.0));
  session.handle(R"({"type": "step"})");
  CHECK(session.advance(1.0));
  CHECK(serve::decodeFrame(session.frame()).header.frame == frame + 1);

  // A slice used up after the first frame: the other frames due are dropped, not carried
  // (the world runs slower), and stats say so.
  session.handle(R"({"type": "pause", "paused": false})");
  session.handle(R"({"type": "speed", "speed": 4})");
  textMessages(session);
  session.stats(0, 0);
  CHECK(session.advance(1.0, 0.0));
  CHECK(serve::decodeFrame(session.frame()).header.frame == frame + 2);
  CHECK(session.advance(1.0, serve::kNoSlice));
  CHECK(serve::decodeFrame(session.frame()).header.frame == frame + 6);
  const json shed = json::parse(session.stats(0, 0));
  CHECK(shed["frames_shed"] == 3);
  CHECK(shed["slowed"].get<std::string>().find("3 frames were cut short") != std::string::npos);
  CHECK(json::parse(session.stats(0, 0))["frames_shed"] == 0);
}

// The HUD counts success by the scenario's criterion, for behaviours that land no
// punches too. out_boxing's keeper holds 1.2-1.6 m from the target, facing it, for 1 s.
TEST_CASE("a page counts successes by the scenario's criterion: out_boxing's keeper keeps its distance",
          "[serve][data]") {
  const BoxingAssets outBoxing(true, "out_boxing.yaml", {});
  serve::ViewerSession session(outBoxing.assets);
  const std::vector<json> out = textMessages(session);
  REQUIRE(out.size() == 1);
  CHECK(out[0]["behaviors"][0]["success"].get<std::string>().find("pelvis within 0.2 m of 1.4 m") !=
        std::string::npos);
  for (int f = 0; f < static_cast<int>(20 / session.frameTime()); ++f) session.advance(1.0);
  textMessages(session);
  const json stats = json::parse(session.stats(0, 0));
  INFO(stats.dump());
  CHECK(stats["successes"].get<int>() >= 2);
  CHECK(stats["successes"].get<int>() <= stats["decisions"].get<int>());
}

// A dodge scene opens on the avatar and the scripted opponent it was trained
// against, a body of the same graph (the blue corner), in sparring and crowd modes.
TEST_CASE("a dodge page opens on the avatar and its scripted opponent, in sparring and crowd modes",
          "[serve][data][opponent]") {
  const BoxingAssets dodge(true, "dodge.yaml", {});
  serve::ViewerSession session(dodge.assets);
  json scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["mode"] == "sparring");
  CHECK(scene["avatars"] == 2);
  CHECK(scene["partners"] == json::array({1, 0}));
  CHECK(scene["opponent"] == "pursue");
  CHECK(scene["controller"] == "policy");
  for (int f = 0; f < static_cast<int>(30 / session.frameTime()); ++f) session.advance(1.0);
  session.takeOutbox();
  const json stats = json::parse(session.stats(0, 0));
  INFO(stats.dump());
  // The avatar keeps clear of the opponent for 6 s at a time.
  CHECK(stats["successes"].get<int>() >= 1);
  session.handle(R"({"type": "mode", "mode": "target"})");
  scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["avatars"] == 1);
  CHECK(scene["opponent"].is_null());
  session.handle(R"({"type": "mode", "mode": "crowd", "avatars": 6})");
  scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["partners"] == json::array({1, 0, 3, 2, 5, 4}));
  CHECK(scene["opponent"] == "pursue");
  // Boxing has no opponent: it opens on the boxer and its target.
  const BoxingAssets boxing(/*withPolicy=*/false);
  serve::ViewerSession paper(boxing.assets);
  scene = json::parse(paper.takeOutbox().at(0));
  CHECK(scene["mode"] == "target");
  CHECK(scene["opponent"].is_null());
}

// A learned opponent's scene opens on two fighters, as dodge's does, each playing
// the bundle and told what the other is doing (it opened on one boxer and a dragged target
// until 2026-11-29). The success counter sees the partner's head and strikes as the
// environment tracks them through each action, as eval's trials do.
TEST_CASE("a learned opponent's page opens on two fighters that spar with the bundle",
          "[serve][data][opponent][slow]") {
  // spar_learned.yaml shrunk as in learned_opponent_test: 936 vertices, one round (what the
  // page plays does not depend on how many rounds made the table).
  const BoxingAssets spar(true, "spar_learned.yaml",
                          {"behaviors.spar.discretizer.sectors=2", "behaviors.spar.discretizer.rings=2",
                           "behaviors.spar.discretizer.headings=2", "behaviors.spar.environment.phases=1",
                           "behaviors.spar.environment.rounds=1"});
  serve::ViewerSession page(spar.assets);
  const json scene = json::parse(page.takeOutbox().at(0));
  INFO(scene.dump());
  CHECK(scene["mode"] == "sparring");
  CHECK(scene["avatars"] == 2);
  CHECK(scene["partners"] == json::array({1, 0}));
  for (int f = 0; f < static_cast<int>(20 / page.frameTime()); ++f) page.advance(1.0);
  page.takeOutbox();
  const json stats = json::parse(page.stats(0, 0));
  INFO(stats.dump());
  CHECK(stats["decisions"].get<int>() > 0);
  CHECK(stats["successes"].get<int>() <= stats["decisions"].get<int>());
  // Both corners play the page's controller (no partner bundle given), told what the other does.
  CHECK(scene["controller"] == "policy");
  CHECK(scene["opponent"].is_null());
}

// A turning target's grid repeats every position per turn rate. The values view
// shows the positions of the target's motion at the decision: its turn layer, its speed
// layer and its heading. intercept's targets walk and turn in target mode; one the page
// drags stands, and then the view shows the straight, speed-0 layers, where every turn layer
// holds the same values, as the table shows.
TEST_CASE("an intercept page's values view shows the layers of its target's motion", "[serve][data][turning]") {
  const BoxingAssets intercept(true, "intercept.yaml", {});
  serve::ViewerSession session(intercept.assets);
  session.takeOutbox();
  for (int f = 0; f < 60; ++f) session.advance(1.0);
  session.takeOutbox();
  const Discretizer& grid = *intercept.assets->session->behaviors.at(0).discretizer;
  REQUIRE(grid.turnAxis() != nullptr);
  REQUIRE(grid.turnAxis()->vertices.size() == 5);
  const QTable& q = intercept.assets->session->bundle.behaviors.at("approach").table;
  const std::size_t positions = 13 * 5;  // sectors x rings of one heading, speed and turn
  // The maxima the table holds on the positions of one heading at vertex `first` on.
  auto maxima = [&](std::size_t state, std::size_t first) {
    std::vector<double> out;
    for (std::size_t v = first; v < first + positions; ++v) {
      const float* row = q.row(state, v);
      out.push_back(*std::max_element(row, row + q.actionsOf(state)));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  auto shownValues = [](const json& values) {
    std::vector<double> shown;
    for (const json& p : values["points"]) shown.push_back(p[3].get<double>());
    std::sort(shown.begin(), shown.end());
    return shown;
  };
  auto same = [](const std::vector<double>& a, const std::vector<double>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t k = 0; k < a.size(); ++k)
      if (std::abs(a[k] - b[k]) > 1e-4) return false;
    return true;
  };

  // A walking target: the view is one heading's slice of its speed and turn layers. A
  // target is placed again every 3 s with a new motion; wait for one nearest a layer above
  // speed 0 (speeds are drawn from 0 to 1 m/s, the layers at 0, 0.5 and 1).
  json moving;
  for (int tries = 0; tries < 20 && !(moving.contains("speed") && moving["speed"].get<double>() > 0); ++tries) {
    for (int f = 0; f < 45; ++f) session.advance(1.0);
    session.takeOutbox();
    session.handle(R"({"type": "values", "behavior": "approach"})");
    const std::vector<json> out = textMessages(session);
    REQUIRE(out.size() == 1);
    moving = out[0];
    session.handle(R"({"type": "values", "behavior": null})");
  }
  REQUIRE(moving["speed"].get<double>() > 0);
  REQUIRE(moving["points"].size() == positions);
  const GridAxis& speeds = *grid.axis(AxisRole::Speed);
  const auto speedLayer = static_cast<std::size_t>(
      std::find(speeds.vertices.begin(), speeds.vertices.end(), moving["speed"].get<double>()) -
      speeds.vertices.begin());
  REQUIRE(speedLayer < speeds.vertices.size());
  const std::vector<double>& rates = grid.turnAxis()->vertices;
  std::size_t turnLayer = rates.size();
  for (std::size_t k = 0; k < rates.size(); ++k)
    if (std::abs(rates[k] * 180 / M_PI - moving["turn_deg_s"].get<double>()) < 1e-9) turnLayer = k;
  REQUIRE(turnLayer < rates.size());
  const std::size_t layer = turnLayer * grid.turnVertexCount() + speedLayer * grid.layerVertexCount();
  bool found = false;
  for (std::size_t h = 0; h < 6 && !found; ++h)
    found = same(shownValues(moving), maxima(moving["state"].get<std::size_t>(), layer + h * positions));
  CHECK(found);

  // Dragged, the target stands: speed 0, the straight layer, heading 0 (the fourth of six:
  // a dragged target's heading at a decision); every turn layer holds the same maxima there.
  session.handle(R"({"type": "move_target", "position": [0.5, 1.2, 0.8]})");
  for (int f = 0; f < 60; ++f) session.advance(1.0);
  session.takeOutbox();
  session.handle(R"({"type": "values", "behavior": "approach"})");
  const std::vector<json> out = textMessages(session);
  REQUIRE(out.size() == 1);
  const json& values = out[0];
  CHECK(values["speed"] == 0.0);
  CHECK(values["stance"].is_null());  // intercept has no stances
  CHECK(values["behavior_stance"].is_null());
  CHECK(values["turn_deg_s"] == 0.0);
  REQUIRE(values["points"].size() == positions);
  const auto state = values["state"].get<std::size_t>();
  for (std::size_t turn = 0; turn < 5; ++turn) {
    const std::size_t first = turn * grid.turnVertexCount() + 3 * positions;
    for (std::size_t v = first; v < first + positions; ++v) CHECK(grid.vertexState(v).speed == 0);
    CHECK(same(shownValues(values), maxima(state, first)));
  }
}

// boxing.yaml's sparring and crowds play boxing_spar.yaml's behaviour, which keeps
// a fighting distance; target mode keeps the paper's two behaviours.
TEST_CASE("boxing's sparring plays boxing_spar's behaviour at a fighting distance and its target mode the paper's",
          "[serve][data][outcome]") {
  const BoxingAssets boxing(
      true, "boxing.yaml",
      {"behaviors.approach.learner.type=value_iteration", "behaviors.hit.learner.type=value_iteration"},
      /*sparring=*/true);
  serve::ViewerSession session(boxing.assets);
  json scene = json::parse(session.takeOutbox().at(0));
  auto names = [](const json& message) {
    std::vector<std::string> out;
    for (const json& b : message["behaviors"]) out.push_back(b["name"]);
    return out;
  };
  CHECK(scene["mode"] == "target");
  CHECK(scene["scenario"] == "boxing");
  CHECK(names(scene) == std::vector<std::string>{"approach", "hit"});
  // A lesson on the paper's hit, then sparring: the lesson ends (its behaviour is not
  // sparring's), the scene is boxing_spar's, played by its own trained table.
  session.handle(R"({"type": "learn", "command": "start", "behavior": "hit", "budget": 1000})");
  CHECK(json::parse(session.takeOutbox().at(0))["type"] == "lesson");
  session.handle(R"({"type": "mode", "mode": "sparring"})");
  std::vector<std::string> out = session.takeOutbox();
  REQUIRE(out.size() == 2);
  CHECK(json::parse(out[0]) == json{{"type", "lesson"}, {"behavior", nullptr}});
  scene = json::parse(out[1]);
  CHECK(scene["mode"] == "sparring");
  CHECK(scene["scenario"] == "boxing_spar");
  CHECK(names(scene) == std::vector<std::string>{"spar_square", "spar", "spar_turned"});  // its three stances
  for (int k = 0; k < 3; ++k) CHECK(scene["behaviors"][static_cast<std::size_t>(k)]["stance"] == k);
  CHECK(scene["controller"] == "policy");
  CHECK(scene["behaviors"][0]["vertices"].get<int>() > 0);  // the bundle's table, not a search
  CHECK(scene["note"].get<std::string>().find("Sparring plays") != std::string::npos);
  session.handle(R"({"type": "weights", "weights": {"hit": 2}})");
  CHECK_THAT(json::parse(session.takeOutbox().at(0))["message"].get<std::string>(),
             Catch::Contains("expected behaviour names from spar_square, spar, spar_turned, found \"hit\""));
  session.handle(R"({"type": "values", "behavior": "spar"})");
  const json sparValues = json::parse(session.takeOutbox().at(0));
  CHECK(sparValues["behavior"] == "spar");
  CHECK(sparValues["behavior_stance"] == 1);  // spar is stance 1 of 3; avatar 0 holds one
  REQUIRE(sparValues["stance"].is_number_integer());
  CHECK(sparValues["stance"].get<int>() >= 0);
  CHECK(sparValues["stance"].get<int>() < 3);
  // 20 s of sparring: the pelvises stay a fighting distance apart (the paper's behaviours
  // close in to 0.66 m, boxing_spar's bouts measure 1.17 m), and values of spar follow.
  int values = 0;
  const double spar = medianPelvisDistance(session, 20, &values);
  CHECK(spar >= 0.9);
  CHECK(values >= 10);
  // A crowd plays it too; back in target mode, the paper's two behaviours and no values.
  session.handle(R"({"type": "mode", "mode": "crowd", "avatars": 4})");
  scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["scenario"] == "boxing_spar");
  session.handle(R"({"type": "mode", "mode": "target"})");
  scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["scenario"] == "boxing");
  CHECK(names(scene) == std::vector<std::string>{"approach", "hit"});
  CHECK(scene["controller"] == "policy");
  for (int f = 0; f < 30; ++f) {
    session.advance(1.0);
    for (const std::string& m : session.takeOutbox()) CHECK(json::parse(m)["type"] != "values");
  }
  // --sparring-scenario none: the paper's behaviours spar, and close in.
  const BoxingAssets own;
  serve::ViewerSession paper(own.assets);
  paper.handle(R"({"type": "mode", "mode": "sparring"})");
  paper.takeOutbox();
  const double close = medianPelvisDistance(paper, 20, nullptr);
  INFO("median pelvis distance: boxing_spar " << spar << " m, the paper's behaviours " << close << " m");
  CHECK(close < spar - 0.2);
}

// `mgrl serve --partner-policy DIR`: the second fighter of each pair plays a
// bundle of its own, greedily, as `mgrl simulate --partner-policy` does.
TEST_CASE("serve --partner-policy: the second fighter of each pair plays its own bundle", "[serve][data]") {
  const BoxingAssets spar(true, "boxing_spar.yaml", {});
  // A partner trained on the same graph and grid to keep 2.5 m away instead of 1.15 m, and
  // not to punch nor to mind its facing (its reward without the contact and facing terms).
  test::TempDir dir("serve-partner");
  std::string text = readFile(fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing_spar.yaml");
  const std::string contact = "        - {term: contact, effector: fists, radius: 0.7, weight: 3}\n";
  REQUIRE(text.find("d0: 1.15, sigma: 0.2") != std::string::npos);
  REQUIRE(text.find(contact) != std::string::npos);
  const std::string distance = "d0: 1.15, sigma: 0.2";  // every stance's
  for (std::size_t at = text.find(distance); at != std::string::npos; at = text.find(distance))
    text.replace(at, distance.size(), "d0: 2.5, sigma: 0.2");
  for (std::size_t at = text.find(contact); at != std::string::npos; at = text.find(contact))
    text.erase(at, contact.size());
  // And without the stances' facing terms: it minds the distance alone.
  const std::string facing = "        - {term: facing, prefer: stance";
  for (std::size_t at = text.find(facing); at != std::string::npos; at = text.find(facing))
    text.erase(at, text.find('\n', at) + 1 - at);
  writeFile(dir.path / "far.yaml", text);
  app::TrainOptions far = spar.train;
  far.scenario = dir.path / "far.yaml";
  far.out = dir.path / "far-policy";
  app::runTrain(far);
  auto options = [&](const fs::path& partner, int round) {
    serve::ServeOptions o;
    static_cast<SessionOptions&>(o) = spar.train;
    o.policy = spar.train.out;
    o.sparringScenario = "none";
    o.partnerPolicy = partner;
    o.partnerRound = round;
    return o;
  };
  auto sparring = [](serve::ViewerSession& page) {
    page.takeOutbox();
    page.handle(R"({"type": "mode", "mode": "sparring"})");
    return json::parse(page.takeOutbox().at(0));
  };
  serve::ViewerSession own(spar.assets), near(serve::loadViewerAssets(options(spar.train.out, 0))),
      again(serve::loadViewerAssets(options(spar.train.out, 0))), away(serve::loadViewerAssets(options(far.out, 0)));
  // It opens in target mode as without a partner (only a scripted opponent's scene opens
  // sparring), and the note names the partner only where there are pairs.
  const json opening = json::parse(near.takeOutbox().at(0));
  CHECK(opening["mode"] == "target");
  CHECK(opening["note"].get<std::string>().find("second fighter") == std::string::npos);
  CHECK(sparring(own)["opponent"].is_null());
  CHECK(sparring(near)["opponent"] == "partner_policy");
  sparring(again);
  const json scene = sparring(away);
  CHECK(scene["opponent"] == "partner_policy");
  CHECK(scene["controller"] == "policy");
  CHECK_THAT(scene["note"].get<std::string>(),
             Catch::Contains("The second fighter of each pair plays") && Catch::Contains("far-policy"));
  // The partner's pelvis, frame by frame: the same bundle twice, the same bout (the world
  // is deterministic); another bundle, another bout, though the first fighter plays the
  // same tables.
  auto partnerPath = [](serve::ViewerSession& page, int frames) {
    std::vector<Eigen::Vector3d> path;
    for (int f = 0; f < frames; ++f) {
      page.advance(1.0);
      page.takeOutbox();
      path.push_back(serve::decodeFrame(page.frame()).avatars.at(1).at(0));
    }
    return path;
  };
  const int frames = static_cast<int>(10 / near.frameTime());
  const auto nearPath = partnerPath(near, frames);
  CHECK(partnerPath(again, frames) == nearPath);
  CHECK(partnerPath(away, frames) != nearPath);
  // The partner that wants 2.5 m (and no punches) holds the pair further apart than the
  // scenario's own bundle does.
  const double withOwn = medianPelvisDistance(near, 20, nullptr), withFar = medianPelvisDistance(away, 20, nullptr);
  INFO("median pelvis distance: partner plays the scenario's bundle " << withOwn << " m, the far one's " << withFar
                                                                      << " m");
  CHECK(withOwn < 1.6);
  CHECK(withFar > withOwn);
  // Refusals, each in one line naming the flag.
  auto refusal = [&](serve::ServeOptions o) {
    try {
      serve::loadViewerAssets(o);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(refusal(options("", 2)), Catch::StartsWith("--partner-round: expected --partner-policy DIR as well"));
  CHECK_THAT(refusal(options(far.out, 1)),
             Catch::StartsWith("--partner-policy: ") && Catch::Contains("expected self-play round 1's table"));
  CHECK_THAT(refusal(options(dir.path / "absent", 0)),
             Catch::StartsWith("--partner-policy: ") && Catch::Contains("absent"));
  serve::ServeOptions dodge = options(far.out, 0);
  dodge.scenario = fs::path(MGRL_SOURCE_DIR) / "scenarios" / "dodge.yaml";
  dodge.policy.clear();
  CHECK_THAT(refusal(dodge), Catch::StartsWith("--partner-policy: expected a scenario whose partners play the page's "
                                               "controller") &&
                                 Catch::Contains("scripted opponent (pursue)"));
}

// A sparring scenario that cannot be used is refused at start, in one line.
TEST_CASE("serve refuses a sparring scenario it cannot use, naming it", "[serve][data]") {
  test::TempDir dir("serve-sparring");
  const std::string boxing = readFile(fs::path(MGRL_SOURCE_DIR) / "scenarios" / "boxing.yaml");
  auto scenarioWith = [&](const std::string& name, const std::string& line) {
    std::string text = boxing;
    text.replace(text.find("sparring_scenario: boxing_spar.yaml"),
                 std::string("sparring_scenario: boxing_spar.yaml").size(), line);
    writeFile(dir.path / name, text);
    return dir.path / name;
  };
  auto refusal = [&](const fs::path& scenario, const std::string& flag) {
    serve::ServeOptions options;
    options.scenario = scenario;
    options.dataDir = test::mocap();
    options.cacheDir = dir.path / "cache";
    options.sparringScenario = flag;
    try {
      serve::loadViewerAssets(options);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(refusal(scenarioWith("missing.yaml", "sparring_scenario: nope.yaml"), ""),
             Catch::Contains("missing.yaml:") && Catch::Contains("sparring_scenario: expected a scenario file") &&
                 Catch::Contains("found \"nope.yaml\" (no file at "));
  CHECK_THAT(refusal(scenarioWith("empty.yaml", "sparring_scenario: ''"), "none"),
             Catch::Contains("empty.yaml:") && Catch::Contains("sparring_scenario: expected a scenario file") &&
                 Catch::Contains("found an empty string"));
  // Other commands do not open it: a copy of boxing.yaml without its companion still loads.
  CHECK(loadScenario(scenarioWith("copy.yaml", "sparring_scenario: nope.yaml"), test::mocap()).sparringScenario ==
        dir.path / "nope.yaml");
  CHECK_THAT(refusal(scenarioWith("self.yaml", "sparring_scenario: self.yaml"), ""),
             Catch::Contains("sparring_scenario: expected another scenario than this one"));
  const fs::path scenarios = fs::path(MGRL_SOURCE_DIR) / "scenarios";
  // A scene with a scripted opponent spars with it; a companion with one is no sparring partner.
  CHECK_THAT(refusal(scenarios / "dodge.yaml", (scenarios / "boxing_spar.yaml").string()),
             Catch::Contains("--sparring-scenario: expected a scenario without a scripted opponent"));
  CHECK_THAT(refusal(scenarios / "boxing.yaml", (scenarios / "dodge.yaml").string()),
             Catch::Contains("sparring scenario ") &&
                 Catch::Contains("dodge.yaml: expected a scenario without a scripted opponent"));
  CHECK_THAT(refusal(scenarios / "boxing.yaml", (dir.path / "absent.yaml").string()),
             Catch::Contains("sparring scenario ") && Catch::Contains("absent.yaml"));
}

TEST_CASE("with no policy bundle, the page is told and the online search runs", "[serve][data]") {
  const BoxingAssets boxing(/*withPolicy=*/false);
  serve::ViewerSession session(boxing.assets);
  const json scene = json::parse(session.takeOutbox().at(0));
  CHECK(scene["controller"] == "online_search");
  CHECK(scene["controllers"] == json::array({"online_search", "random"}));
  CHECK(scene["note"].get<std::string>().find("mgrl train") != std::string::npos);
  session.handle(R"({"type": "controller", "controller": "policy"})");
  CHECK(json::parse(session.takeOutbox().at(0))["message"].get<std::string>().find("no policy bundle") !=
        std::string::npos);
  session.handle(R"({"type": "values", "behavior": "hit"})");
  CHECK(json::parse(session.takeOutbox().at(0))["message"].get<std::string>().find("expected a policy bundle") !=
        std::string::npos);
}

// The learn panel steps the paper's Q-learning on a table of the page's own, and
// live retraining swaps a behaviour's table for value iteration's on changed parameters.
TEST_CASE("a page's lesson steps Q-learning and a retraining switches the policy", "[serve][data][slow]") {
  const BoxingAssets boxing;
  serve::ViewerSession session(boxing.assets);
  const json original = textMessages(session).at(0)["behaviors"][1];
  REQUIRE(original["name"] == "hit");
  CHECK(original["parameters"]["reward.contact_radius"] == 0.15);
  auto only = [&](const char* type) {
    std::vector<json> found;
    for (const json& m : textMessages(session))
      if (m["type"] == type) found.push_back(m);
    REQUIRE(found.size() == 1);
    return found[0];
  };
  session.handle(R"({"type": "learn", "command": "step"})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("expected a lesson started first"));
  session.handle(R"({"type": "learn", "command": "start", "behavior": "kick"})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("expected one of approach, hit, found \"kick\""));

  session.handle(R"({"type": "learn", "command": "start", "behavior": "approach", "seed": 3, "budget": 50})");
  const json lesson = only("lesson");
  CHECK(lesson["updates"] == 0);
  CHECK(lesson["budget"] == 50);
  session.handle(R"({"type": "learn", "command": "step", "steps": 49})");
  const json step = only("learn_step");
  CHECK(step["update"] == 49);
  CHECK(step["taken"] == 49);
  CHECK(step["done"] == false);
  for (const json& v : step["vertices"])
    CHECK(v["after"].get<double>() ==
          Approx(v["before"].get<double>() + step["alpha"].get<double>() * (v["backup"].get<double>() - v["before"].get<double>()))
              .margin(1e-6));
  // Running: the steps come with the clock, and stop at the budget.
  session.handle(R"({"type": "learn", "command": "run", "rate": 2000})");
  session.advance(1.0);
  const json last = only("learn_step");
  CHECK(last["update"] == 50);
  CHECK(last["done"] == true);
  session.handle(R"({"type": "learn", "command": "step"})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("budget of 50 actions is spent"));

  // Retraining: a bad value is refused at once, naming it; a good one trains on a thread.
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {"reward.contact_radius": -1}})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("contact_radius"));
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {"reward.nonsense": 1}})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("nonsense"));
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {"discretizer.angles": 100000}})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("angles"));
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {"discretizer.angles": 10}})");
  CHECK(only("retrain")["status"] == "started");
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {"discretizer.angles": 12}})");
  CHECK_THAT(only("error")["message"].get<std::string>(), Catch::Contains("expected no retraining under way"));
  json done, scene;
  for (int k = 0; k < 6000 && done.is_null(); ++k) {  // at most a minute
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    session.advance(0.0);
    for (const json& m : textMessages(session)) {
      if (m["type"] == "retrain") done = m;
      if (m["type"] == "scene") scene = m;
    }
  }
  REQUIRE(done["status"] == "done");
  // Before and after are what `mgrl eval` says on the same 200 trials of 10 s from seed 1:
  // of the bundle as it is, and of a bundle trained by `mgrl train` with the same change
  // (value iteration, as the page's retraining).
  app::EvalOptions eval;
  static_cast<app::LearnOptions&>(eval) = boxing.train;
  eval.policy = boxing.train.out;
  eval.trials = 200;
  const json evalBefore = app::runEval(eval);
  app::TrainOptions changed = boxing.train;
  changed.out = boxing.temp.path / "angles-10";
  changed.cacheDir = boxing.temp.path / "cache";
  changed.sets.push_back("behaviors.hit.discretizer.angles=10");
  app::runTrain(changed);
  static_cast<app::LearnOptions&>(eval) = changed;
  eval.policy = changed.out;
  const json evalAfter = app::runEval(eval);
  // The page's table is the one `mgrl train` writes with the same change, byte for byte.
  const json manifest = json::parse(readFile(changed.out / "manifest.json"));
  CHECK(done["table_hash"] == manifest["behaviors"]["hit"]["table"]["hash"]);
  CHECK(done["table_hash"] !=
        json::parse(readFile(boxing.train.out / "manifest.json"))["behaviors"]["hit"]["table"]["hash"]);
  INFO("page: " << done["before"].dump() << " -> " << done["after"].dump() << "; eval: " << evalBefore["success_rate"]
                << " -> " << evalAfter["success_rate"]);
  CHECK(done["before"]["success_rate"].get<double>() == Approx(evalBefore["success_rate"].get<double>()).margin(1e-9));
  CHECK(done["after"]["success_rate"].get<double>() == Approx(evalAfter["success_rate"].get<double>()).margin(1e-9));
  CHECK(done["before"]["mean_return"].get<double>() == Approx(evalBefore["mean_return"].get<double>()).margin(1e-3));
  CHECK(done["after"]["mean_return"].get<double>() == Approx(evalAfter["mean_return"].get<double>()).margin(1e-3));
  CHECK(done["before"]["mean_return"] != done["after"]["mean_return"]);  // the new table does change the policy
  const json& hit = scene["behaviors"][1];
  CHECK(hit["retrained"]["discretizer.angles"] == 10);
  CHECK(hit["parameters"]["discretizer.angles"] == 10);
  CHECK(hit["vertices"] == done["vertices"]);
  CHECK(hit["vertices"].get<std::size_t>() * 2 == original["vertices"].get<std::size_t>());  // 10 angles, not 20
  // The retrained table is the one the page's values come from.
  session.handle(R"({"type": "values", "behavior": "hit"})");
  const json values = only("values");
  CHECK(values["points"].size() * 6 == done["vertices"].get<std::size_t>());  // one of 6 layers
  // Back to the bundle.
  session.handle(R"({"type": "retrain", "behavior": "hit", "set": {}})");
  std::vector<json> back = textMessages(session);
  REQUIRE(back.size() == 2);
  CHECK(back[1]["status"] == "reverted");
  CHECK_FALSE(back[0]["behaviors"][1].contains("retrained"));
}


TEST_CASE("the server serves the page's files, refuses traversal and other methods", "[serve][data]") {
  const BoxingAssets boxing;
  RunningServer running(boxing.assets, 4);
  const HttpReply index = get(running.port(), "/");
  CHECK(index.status == 200);
  CHECK(index.type == "text/html; charset=utf-8");
  CHECK(index.body == "<!doctype html><title>mgrl</title>");
  CHECK(get(running.port(), "/viewer.js").type == "text/javascript; charset=utf-8");
  CHECK(get(running.port(), "/node_modules/three/build/three.module.js").status == 200);
  CHECK(get(running.port(), "/missing.js").status == 404);
  for (const char* hostile : {"/../CMakeLists.txt", "/%2e%2e/CMakeLists.txt", "/..%2f..%2fetc/passwd", "/%00"}) {
    INFO(hostile);
    CHECK(get(running.port(), hostile).status == 400);
  }
  CHECK(get(running.port(), "/", http::verb::post).status == 405);
  CHECK(get(running.port(), "/", http::verb::head).status == 200);
}

TEST_CASE("the server refuses a web folder, address or port it cannot use, in one line", "[serve][data]") {
  const BoxingAssets boxing;
  test::TempDir web("serve-bad-web");
  serve::ServerOptions options;
  options.port = 0;
  options.webRoot = web.path;
  REQUIRE_THROWS_WITH(serve::Server(boxing.assets, options),
                      Catch::Contains("expected the viewer's folder with index.html, found no index.html"));
  writeFile(web.path / "index.html", "<!doctype html>");
  REQUIRE_THROWS_WITH(serve::Server(boxing.assets, options),
                      Catch::Contains("expected three.js in node_modules/three (installed by scripts/setup.sh), found "
                                      "none: run `npm ci --prefix"));
  writeFile(web.path / "node_modules" / "three" / "build" / "three.module.js", "export {};");
  options.host = "localhost:80";
  REQUIRE_THROWS_WITH(serve::Server(boxing.assets, options), "--host: expected an IP address, found localhost:80");
  options.host = "127.0.0.1";
  const serve::Server first(boxing.assets, options);
  options.port = first.port();  // taken
  REQUIRE_THROWS_WITH(serve::Server(boxing.assets, options),
                      Catch::Contains(fmt::format("--port {}: cannot listen on 127.0.0.1:{}: ", first.port(), first.port())));

  serve::ServeCommandOptions command;
  command.port = 70000;
  REQUIRE_THROWS_WITH(serve::runServe(command), "--port: expected a port in [0, 65535] (0: any free one), found 70000");
}

TEST_CASE("hostile pages get an error or a closed socket while a good page keeps receiving frames",
          "[serve][data]") {
  const BoxingAssets boxing;
  RunningServer running(boxing.assets, 6);
  Page good(running.port());
  const Page::Message scene = good.readUntil(false, "scene");
  REQUIRE_FALSE(scene.error);
  const std::size_t joints = json::parse(scene.data)["joints"].size();
  auto frameNumber = [&](Page& page) {
    const Page::Message m = page.readUntil(true);
    REQUIRE_FALSE(m.error);
    const serve::DecodedFrame frame = serve::decodeFrame(
        std::span(reinterpret_cast<const std::uint8_t*>(m.data.data()), m.data.size()));
    REQUIRE(frame.header.joints == joints);
    return frame.header.frame;
  };
  const std::uint32_t first = frameNumber(good);

  {  // malformed: one error back, and the page goes on
    Page page(running.port());
    REQUIRE_FALSE(page.send("{\"type\": \"mode\", \"mode\": "));
    const Page::Message error = page.readUntil(false, "error");
    REQUIRE_FALSE(error.error);
    CHECK(json::parse(error.data)["message"] == "message: expected a JSON object, found text that is not JSON");
    REQUIRE_FALSE(page.send(R"({"type": "mode", "mode": "sparring"})"));
    const Page::Message again = page.readUntil(false, "scene");
    REQUIRE_FALSE(again.error);
    CHECK(json::parse(again.data)["avatars"] == 2);
  }
  {  // oversized: closed with 1009
    Page page(running.port());
    page.send(std::string(serve::Limits::kMessageBytes + 1, 'x'));
    CHECK(page.closeCode() == 1009);
  }
  {  // binary: closed with 1003
    Page page(running.port());
    page.send("\x01\x02", /*binary=*/true);
    CHECK(page.closeCode() == 1003);
  }
  {  // a flood: closed with 1008
    Page page(running.port());
    for (int i = 0; i < serve::Limits::kMessagesPerSecond + 50; ++i)
      if (page.send(R"({"type": "speed", "speed": 1})")) break;
    CHECK(page.closeCode() == 1008);
  }
  {  // half a frame, then gone
    net::io_context ioc;
    tcp::socket raw(ioc);
    raw.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), running.port()));
    const std::string upgrade =
        fmt::format("GET /ws HTTP/1.1\r\nHost: 127.0.0.1:{}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                    "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
                    running.port());
    net::write(raw, net::buffer(upgrade));
    std::string reply(12, '\0');
    net::read(raw, net::buffer(reply.data(), reply.size()));
    CHECK(reply == "HTTP/1.1 101");
    const unsigned char partial[] = {0x81, 0x80 | 100, 1, 2, 3, 4, 'a', 'b', 'c'};  // text, masked, 100 bytes; 3 sent
    net::write(raw, net::buffer(partial, sizeof partial));
    raw.close();
  }
  {  // the page limit: the seventh is refused with 503 (good + six)
    std::vector<std::unique_ptr<Page>> pages;
    // Closed pages leave within moments; wait for the count to settle.
    for (int i = 0; i < 100 && running.server->sessions() > 1; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    for (int i = 0; i < 5; ++i) pages.push_back(std::make_unique<Page>(running.port()));
    const HttpReply refused = get(running.port(), "/ws", http::verb::get, /*upgrade=*/true);
    CHECK(refused.status == 503);
    CHECK(refused.body == "expected at most 6 pages at once; close one\n");
  }
  // Through all of it the good page's world went on, and files are still served.
  const std::uint32_t later = frameNumber(good);
  CHECK(later > first);
  CHECK(get(running.port(), "/").status == 200);
}

}  // namespace
}  // namespace mgrl::serve_test
