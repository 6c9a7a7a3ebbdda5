#pragma once
/// \file
/// What `mgrl serve`'s connections share (server.cpp accepts them and answers HTTP;
/// page_session.cpp runs a page's WebSocket): the server's options, assets and origin
/// policy, the count of pages open, and the refusal log. Internal to app/serve.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "serve/origin.hpp"
#include "serve/server.hpp"

namespace mgrl::serve {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

// What connections share. Owned jointly by the server and every connection, so that the
// connections the io_context destroys when it goes can still count themselves out.
struct Shared {
  std::shared_ptr<const ViewerAssets> assets;
  ServerOptions options;
  std::filesystem::path root;
  std::optional<OriginPolicy> origins;  ///< set once the port is known
  std::atomic<int> sessions{0};
  /// Costly page messages (a crowd's build) take turns: none starts before this time,
  /// which each one sets to its end plus as long again as it took (page_session.cpp).
  Clock::time_point costlyFree{};
  // Refusals of foreign Host or Origin headers: logged at most once a second (a hostile
  // page may send thousands), with how many were not.
  Clock::time_point lastRefusalLog{};
  std::size_t refusalsNotLogged = 0;

  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }
  void refused(const std::string& why) {
    const auto now = Clock::now();
    if (now - lastRefusalLog < std::chrono::seconds(1)) {
      ++refusalsNotLogged;
      return;
    }
    log(refusalsNotLogged ? fmt::format("serve: refused a request: {} ({} more refused since the last such line)", why,
                                        refusalsNotLogged)
                          : fmt::format("serve: refused a request: {}", why));
    lastRefusalLog = now;
    refusalsNotLogged = 0;
  }
};

/// Takes over `socket`, whose HTTP `request` asks for the WebSocket upgrade on /ws (its
/// Host, Origin and the page limit checked), and runs the page until it closes.
void startPageSession(tcp::socket socket, std::shared_ptr<Shared> server,
                      const http::request<http::empty_body>& request);

}  // namespace mgrl::serve
