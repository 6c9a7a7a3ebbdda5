#pragma once
/// \file
/// The HTTP and WebSocket server of `mgrl serve` (docs/viewer-protocol.md), on Boost.Beast
/// and Boost.Asio with one network thread: static files from the web folder, and one
/// ViewerSession per page on `/ws`, ticked at the world's frame rate.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "mgrl/core/error.hpp"
#include "serve/viewer.hpp"

namespace mgrl::serve {

struct ServerOptions {
  std::string host = "127.0.0.1";
  std::uint16_t port = 8080;        ///< 0: any free port (see Server::port())
  std::filesystem::path webRoot;    ///< the folder of index.html
  int maxSessions = Limits::kMaxSessions;
  /// Origins besides the server's own whose pages may open the WebSocket, and whose host
  /// names requests may carry (--allow-origin; see serve/origin.hpp).
  std::vector<std::string> allowOrigins;
  WarningSink log;                  ///< connections and failures (stderr); may be empty
};

class Server {
 public:
  /// Binds and listens. Throws mgrl::Error if the web folder has no index.html or the
  /// address cannot be bound.
  Server(std::shared_ptr<const ViewerAssets> assets, ServerOptions options);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  /// The port listened on.
  std::uint16_t port() const;
  /// Serves until stop() (or SIGINT/SIGTERM once stopOnSignals() was called).
  void run();
  /// Stops run() soon; callable from any thread.
  void stop();
  /// Makes SIGINT and SIGTERM stop run().
  void stopOnSignals();
  /// Pages connected now.
  int sessions() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mgrl::serve
