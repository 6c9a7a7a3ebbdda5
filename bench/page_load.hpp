#pragma once
// A load on `mgrl serve` from one thread: WebSocket pages that each read as fast as they can
// and time the frames they get (tests/serve_hardening_test.cpp, mgrl_bench_serve --shared).
#include <algorithm>
#include <chrono>
#include <memory>
#include <string>
#include <utility>  // before Boost 1.74's asio, which uses std::exchange without it
#include <vector>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

namespace mgrl::bench {

namespace beast = boost::beast;
namespace net = boost::asio;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

/// Pages on one thread, each reading as fast as it can (an async read always waiting),
/// timing the frames it gets: the load of the shared-budget test and benchmark.
struct PageLoad {
  net::io_context ioc;
  struct Page {
    explicit Page(net::io_context& ioc) : ws(ioc) {}
    websocket::stream<beast::tcp_stream> ws;
    beast::flat_buffer buffer;
    std::vector<Clock::time_point> frames;
    json stats;
    int closeCode = 0;
    bool failed = false;
  };
  std::vector<std::unique_ptr<Page>> pages;

  Page& open(std::uint16_t port, const std::vector<std::string>& messages) {
    auto c = std::make_unique<Page>(ioc);
    beast::get_lowest_layer(c->ws).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    c->ws.handshake(fmt::format("127.0.0.1:{}", port), "/ws");
    for (const std::string& m : messages) c->ws.write(net::buffer(m));
    read(*c);
    pages.push_back(std::move(c));
    return *pages.back();
  }
  void read(Page& c) {
    c.ws.async_read(c.buffer, [this, &c](beast::error_code ec, std::size_t) {
      if (ec) {
        if (ec == websocket::error::closed) c.closeCode = static_cast<int>(c.ws.reason().code);
        else c.failed = true;
        return;
      }
      if (c.ws.got_binary()) {
        c.frames.push_back(Clock::now());
      } else {
        json m = json::parse(beast::buffers_to_string(c.buffer.data()));
        if (m["type"] == "stats") c.stats = std::move(m);
      }
      c.buffer.consume(c.buffer.size());
      read(c);
    });
  }
  void runFor(double seconds) { ioc.run_for(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds))); }
};

/// What `heavy` pages with the heaviest legal settings (crowds of 2,000 on the online
/// search at speed 4) leave to one light page (one boxer, its policy) on the same server.
struct HeavyBesideLight {
  int heavy = 0;
  double lightFramesPerSecond = 0, lightLongestGap = 0;  ///< s
  std::size_t heavyFrames = 0;  ///< all heavy pages together, over the whole run
  std::size_t heavySlowed = 0;  ///< heavy pages whose last stats said they were slowed
  std::size_t heavyClosed = 0;
  bool lightClosed = false, lightSlowed = false;

  std::string summary() const {
    return fmt::format("{} crowds of 2,000 (online search, speed 4) beside one light page: the light page got {:.1f} "
                       "frames/s (longest gap {:.2f} s){}; the heavy pages {} frames in all, {} of them told they are "
                       "slowed, {} closed",
                       heavy, lightFramesPerSecond, lightLongestGap, lightClosed ? ", then was closed" : "", heavyFrames,
                       heavySlowed, heavyClosed);
  }
};

/// Opens the heavy pages, then the light one; lets the crowds build for `warmup` seconds,
/// then counts the light page's frames for `seconds`.
inline HeavyBesideLight heavyBesideLight(std::uint16_t port, int heavy, double warmup, double seconds) {
  PageLoad load;
  for (int i = 0; i < heavy; ++i)
    load.open(port, {R"({"type": "mode", "mode": "crowd", "avatars": 2000})",
                     R"({"type": "controller", "controller": "online_search", "horizon": 3})",
                     R"({"type": "speed", "speed": 4})"});
  PageLoad::Page& light = load.open(port, {});
  load.runFor(warmup);
  const std::size_t before = light.frames.size();
  const auto began = Clock::now();
  load.runFor(seconds);
  HeavyBesideLight r;
  r.heavy = heavy;
  r.lightFramesPerSecond =
      static_cast<double>(light.frames.size() - before) / std::chrono::duration<double>(Clock::now() - began).count();
  for (std::size_t i = before + 1; i < light.frames.size(); ++i)
    r.lightLongestGap = std::max(r.lightLongestGap, std::chrono::duration<double>(light.frames[i] - light.frames[i - 1]).count());
  auto slowed = [](const PageLoad::Page& p) { return p.stats.is_object() && p.stats.value("slowed", json()).is_string(); };
  for (std::size_t i = 0; i + 1 < load.pages.size(); ++i) {
    const PageLoad::Page& p = *load.pages[i];
    r.heavyFrames += p.frames.size();
    r.heavySlowed += slowed(p);
    r.heavyClosed += p.closeCode != 0 || p.failed;
  }
  r.lightClosed = light.closeCode != 0 || light.failed;
  r.lightSlowed = slowed(light) || !light.stats.is_object();
  return r;
}

}  // namespace mgrl::bench
