#pragma once
// What the tests of mgrl serve share: a boxing scenario's viewer assets, the real server on
// a free port, plain HTTP requests and WebSocket pages over real sockets.
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
#include "mgrl/scenario/scenario.hpp"
#include "serve/server.hpp"
#include "serve/viewer.hpp"
#include "test_support.hpp"

namespace mgrl::test::serving {

namespace fs = std::filesystem;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using json = nlohmann::json;

inline void writeFile(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

// Boxing with a policy trained by value iteration (about two seconds with the graph).
struct BoxingAssets {
  test::TempDir temp{"serve"};
  std::shared_ptr<const serve::ViewerAssets> assets;
  app::TrainOptions train;  ///< what made the policy bundle (train.out)

  /// `sparring`: the scenario's own `sparring_scenario` plays sparring and crowds (its
  /// default bundle trained beside, in the same cache); else `--sparring-scenario none`,
  /// so that these tests see the scenario's own behaviours in every mode.
  explicit BoxingAssets(bool withPolicy = true, const std::string& scenario = "boxing.yaml",
                        std::vector<std::string> sets = {"behaviors.approach.learner.type=value_iteration",
                                                         "behaviors.hit.learner.type=value_iteration"},
                        bool sparring = false) {
    train.scenario = fs::path(MGRL_SOURCE_DIR) / "scenarios" / scenario;
    train.dataDir = test::mocap();
    train.cacheDir = temp.path / "cache";
    train.out = temp.path / "policy";
    train.sets = std::move(sets);
    if (withPolicy) {
      // Trained once for every test process of the suite (test::sharedResult): these tests
      // test the viewer, the learning tests the training.
      std::string name = fs::path(scenario).stem().string();
      for (const std::string& set : train.sets) name += "," + set;
      if (sparring) name += ",sparring";
      const fs::path shared = test::sharedResult(fmt::format("serve-{:016x}", std::hash<std::string>{}(name)),
                                                 [&](const fs::path& d) {
                                                   app::TrainOptions t = train;
                                                   t.cacheDir = d / "cache";
                                                   t.out = d / "policy";
                                                   app::runTrain(t);
                                                   if (sparring) {  // its default bundle, where serve looks
                                                     app::TrainOptions spar = t;
                                                     spar.scenario =
                                                         loadScenario(t.scenario, t.dataDir).sparringScenario;
                                                     spar.sets.clear();
                                                     spar.out.clear();
                                                     app::runTrain(spar);
                                                   }
                                                 });
      train.cacheDir = shared / "cache";
      train.out = shared / "policy";
    }
    serve::ServeOptions options;
    static_cast<SessionOptions&>(options) = train;
    if (withPolicy) options.policy = train.out;
    options.sparringScenario = sparring ? "" : "none";
    assets = serve::loadViewerAssets(options);
  }
};

// The server on a free port, in a thread of its own, serving a small web folder.
struct RunningServer {
  test::TempDir web{"serve-web"};
  std::unique_ptr<serve::Server> server;
  std::thread thread;

  RunningServer(std::shared_ptr<const serve::ViewerAssets> assets, int maxSessions,
                std::vector<std::string> allowOrigins = {}, WarningSink log = {}) {
    writeFile(web.path / "index.html", "<!doctype html><title>mgrl</title>");
    writeFile(web.path / "viewer.js", "export const x = 1;");
    writeFile(web.path / "node_modules" / "three" / "build" / "three.module.js", "export {};");
    serve::ServerOptions options;
    options.port = 0;
    options.webRoot = web.path;
    options.maxSessions = maxSessions;
    options.allowOrigins = std::move(allowOrigins);
    options.log = std::move(log);
    server = std::make_unique<serve::Server>(std::move(assets), options);
    thread = std::thread([this] { server->run(); });
  }
  ~RunningServer() {
    server->stop();
    thread.join();
  }
  std::uint16_t port() const { return server->port(); }
};

struct HttpReply {
  int status = 0;
  std::string type, body;
  std::string allow;  ///< the Allow header, if any
};

// Headers of a request as a test sets them: {name, value}; a value of "-" removes the
// header (Host is set to 127.0.0.1:PORT unless given); a name given twice is sent twice.
using Headers = std::vector<std::pair<std::string, std::string>>;

// One request on a fresh connection; `target` is sent as is.
inline HttpReply get(std::uint16_t port, const std::string& target, http::verb verb = http::verb::get,
                     bool upgrade = false, const Headers& headers = {}) {
  net::io_context ioc;
  beast::tcp_stream stream(ioc);
  stream.expires_after(std::chrono::seconds(10));
  stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  http::request<http::empty_body> request{verb, target, 11};
  request.set(http::field::host, fmt::format("127.0.0.1:{}", port));
  std::vector<std::string> named;
  for (const auto& [name, value] : headers) {
    if (value == "-")
      request.erase(name);
    else if (std::find(named.begin(), named.end(), name) != named.end())
      request.insert(name, value);
    else
      request.set(name, value);
    named.push_back(name);
  }
  if (upgrade) {  // a WebSocket handshake by hand, to see the refusal's status
    request.set(http::field::connection, "Upgrade");
    request.set(http::field::upgrade, "websocket");
    request.set(http::field::sec_websocket_key, "dGhlIHNhbXBsZSBub25jZQ==");
    request.set(http::field::sec_websocket_version, "13");
  }
  http::write(stream, request);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.skip(verb == http::verb::head);
  http::read(stream, buffer, parser);
  const auto& response = parser.get();
  return {static_cast<int>(response.result_int()), std::string(response[http::field::content_type]), response.body(),
          std::string(response[http::field::allow])};
}

// A page over a real WebSocket, every read bounded by a timeout.
struct Page {
  net::io_context ioc;
  websocket::stream<beast::tcp_stream> ws{ioc};
  beast::flat_buffer buffer;

  // `origin` empty: no Origin header (not a browser); else the Origin a browser would send.
  explicit Page(std::uint16_t port, const std::string& origin = "") {
    beast::get_lowest_layer(ws).expires_after(std::chrono::seconds(10));
    beast::get_lowest_layer(ws).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    if (!origin.empty())
      ws.set_option(websocket::stream_base::decorator(
          [origin](websocket::request_type& request) { request.set(http::field::origin, origin); }));
    ws.handshake(fmt::format("127.0.0.1:{}", port), "/ws");
  }
  struct Message {
    beast::error_code error;
    bool binary = false;
    std::string data;
  };
  Message read() {
    Message m;
    beast::get_lowest_layer(ws).expires_after(std::chrono::seconds(10));
    buffer.consume(buffer.size());
    ws.async_read(buffer, [&](beast::error_code ec, std::size_t) { m.error = ec; });
    ioc.restart();
    ioc.run();
    m.binary = ws.got_binary();
    m.data = beast::buffers_to_string(buffer.data());
    return m;
  }
  // Reads until a message of the kind asked for (or an error).
  Message readUntil(bool binary, const std::string& textType = "") {
    for (int i = 0; i < 1000; ++i) {
      Message m = read();
      if (m.error) return m;
      if (m.binary == binary && (binary || textType.empty() || json::parse(m.data)["type"] == textType)) return m;
    }
    return {};
  }
  beast::error_code send(const std::string& text, bool binary = false) {
    beast::error_code ec;
    ws.binary(binary);
    ws.write(net::buffer(text), ec);
    return ec;
  }
  // Reads until the server closes; returns the close code it gave (0 if it did not close).
  int closeCode() {
    for (int i = 0; i < 5000; ++i) {
      const Message m = read();
      if (m.error == websocket::error::closed) return static_cast<int>(ws.reason().code);
      if (m.error) return -1;
    }
    return 0;
  }
};

}  // namespace mgrl::test::serving
