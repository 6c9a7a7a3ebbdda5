#pragma once
// A load on `mgrl serve` from one thread: WebSocket pages that each read as fast as they can
// and time the frames they get (tests/serve_hardening_test.cpp, mgrl_bench_serve --shared).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <utility>  // before Boost 1.74's asio, which uses std::exchange without it
#include <vector>

#include <fmt/format.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
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
    std::size_t statsSlowed = 0;     ///< stats messages whose `slowed` was a sentence
    std::size_t messagesWaited = 0;  ///< the stats' messages_waited, summed
    std::string lastSlowed;          ///< the last such sentence
    bool toldWaiting = false;        ///< a `slowed` said the page's messages waited
    // Messages sent asynchronously (send()), one write at a time, as a browser queues them.
    std::deque<std::string> outgoing;
    bool writing = false;
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
        if (m["type"] == "stats") {
          if (m.value("slowed", json()).is_string()) {
            ++c.statsSlowed;
            c.lastSlowed = m["slowed"].get<std::string>();
            c.toldWaiting = c.toldWaiting || c.lastSlowed.find("messages waited") != std::string::npos;
          }
          c.messagesWaited += m.value("messages_waited", std::size_t{0});
          c.stats = std::move(m);
        }
      }
      c.buffer.consume(c.buffer.size());
      read(c);
    });
  }
  // Queues `text` for the page; written after what is queued before it.
  void send(Page& c, std::string text) {
    c.outgoing.push_back(std::move(text));
    write(c);
  }
  void write(Page& c) {
    if (c.writing || c.outgoing.empty() || c.failed || c.closeCode) return;
    c.writing = true;
    c.ws.text(true);
    c.ws.async_write(net::buffer(c.outgoing.front()), [this, &c](beast::error_code ec, std::size_t) {
      c.writing = false;
      c.outgoing.pop_front();
      if (ec) return;
      write(c);
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

/// What pages that flood costly messages leave to a light page and to HTTP: each flooding
/// page alternates a crowd of 2,000 and target mode at `perSecond` messages a second (under
/// the protocol's 200), reading its socket; one light page plays the boxer; a client asks
/// for the page's HTML every 50 ms on a connection of its own.
struct FloodBesideLight {
  int flooding = 0;
  double perSecond = 0;
  std::size_t sent = 0;                                  ///< messages the flooding pages wrote, in all
  double lightFramesPerSecond = 0, lightLongestGap = 0;  ///< s
  std::size_t requests = 0;
  double requestLongest = 0, requestMedian = 0;  ///< s
  std::size_t floodingTold = 0;                  ///< flooding pages told (stats.slowed) that their messages waited
  std::size_t floodingClosed = 0;
  std::size_t messagesWaited = 0;  ///< by all flooding pages, as their stats counted them
  std::string toldExample;         ///< a flooding page's last slowed sentence
  bool lightClosed = false, lightSlowed = false;

  std::string summary() const {
    return fmt::format(
        "{} pages flooding crowd/target switches at {:.0f} messages/s ({} sent) beside one light page and "
        "an HTTP request every 50 ms: the light page got {:.1f} frames/s (longest gap {:.2f} s){}; "
        "{} requests, median {:.1f} ms, longest {:.1f} ms; {} flooding pages told their {} messages "
        "waited, {} closed",
        flooding, perSecond, sent, lightFramesPerSecond, lightLongestGap, lightClosed ? ", then was closed" : "",
        requests, requestMedian * 1e3, requestLongest * 1e3, floodingTold, messagesWaited, floodingClosed);
  }
};

// `flooding` pages alternate a crowd of 2,000 and target mode at `perSecond` messages each
// for `seconds` (each first sent `first`, if given: say, a controller) beside one light page
// and an HTTP request every 50 ms.
inline FloodBesideLight floodBesideLight(std::uint16_t port, int flooding, double perSecond, double seconds,
                                         const std::string& first = {}) {
  namespace http = beast::http;
  PageLoad load;
  std::vector<PageLoad::Page*> floods;
  floods.reserve(static_cast<std::size_t>(flooding));
  for (int i = 0; i < flooding; ++i) floods.push_back(&load.open(port, {}));
  PageLoad::Page& light = load.open(port, {});
  load.runFor(1);  // every page open and playing
  if (!first.empty()) {  // each flooding page's own set-up (say, its controller)
    for (PageLoad::Page* p : floods) load.send(*p, first);
    load.runFor(1);
  }
  FloodBesideLight r;
  r.flooding = flooding;
  r.perSecond = perSecond;
  // The HTTP client, on a thread of its own: a fresh connection each time, as a browser
  // opening the page does.
  std::atomic<bool> stop{false};
  std::vector<double> latencies;
  std::thread poller([&] {
    while (!stop) {
      const auto t = Clock::now();
      try {
        net::io_context ioc;
        beast::tcp_stream stream(ioc);
        stream.expires_after(std::chrono::seconds(10));
        stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
        http::request<http::empty_body> request{http::verb::get, "/", 11};
        request.set(http::field::host, fmt::format("127.0.0.1:{}", port));
        http::write(stream, request);
        beast::flat_buffer buffer;
        http::response<http::string_body> response;
        http::read(stream, buffer, response);
        latencies.push_back(response.result_int() == 200 ? std::chrono::duration<double>(Clock::now() - t).count()
                                                         : 1e9);
      } catch (const std::exception&) {
        latencies.push_back(1e9);
      }
      std::this_thread::sleep_until(t + std::chrono::milliseconds(50));
    }
  });
  const std::size_t before = light.frames.size();
  const auto began = Clock::now();
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1 / perSecond));
  net::steady_timer timer(load.ioc);
  std::size_t tick = 0;
  std::function<void()> next = [&] {
    for (PageLoad::Page* p : floods) {
      load.send(*p, tick % 2 == 0 ? R"({"type": "mode", "mode": "crowd", "avatars": 2000})"
                                  : R"({"type": "mode", "mode": "target"})");
      ++r.sent;
    }
    ++tick;
    timer.expires_at(began + static_cast<long>(tick) * period);
    timer.async_wait([&](beast::error_code ec) {
      if (!ec && Clock::now() - began < std::chrono::duration<double>(seconds)) next();
    });
  };
  next();
  load.runFor(seconds);
  stop = true;
  poller.join();
  r.lightFramesPerSecond =
      static_cast<double>(light.frames.size() - before) / std::chrono::duration<double>(Clock::now() - began).count();
  for (std::size_t i = before + 1; i < light.frames.size(); ++i)
    r.lightLongestGap =
        std::max(r.lightLongestGap, std::chrono::duration<double>(light.frames[i] - light.frames[i - 1]).count());
  r.requests = latencies.size();
  if (!latencies.empty()) {
    std::sort(latencies.begin(), latencies.end());
    r.requestLongest = latencies.back();
    r.requestMedian = latencies[latencies.size() / 2];
  }
  for (const PageLoad::Page* p : floods) {
    r.floodingTold += p->messagesWaited > 0 && p->toldWaiting;
    r.messagesWaited += p->messagesWaited;
    r.floodingClosed += p->closeCode != 0 || p->failed;
    if (!p->lastSlowed.empty()) r.toldExample = p->lastSlowed;
  }
  r.lightClosed = light.closeCode != 0 || light.failed;
  r.lightSlowed = light.statsSlowed > 0 || !light.stats.is_object();
  return r;
}

}  // namespace mgrl::bench
