#pragma once
/// \file
/// Which `Host` and `Origin` headers `mgrl serve` answers (docs/viewer-protocol.md, "Who
/// may connect"). A server on the loopback address is still reachable by any web page the
/// user visits: a page of another site may open a WebSocket to it (its `Origin` says so),
/// and a name of the attacker's that resolves to 127.0.0.1 (DNS rebinding) sends that name
/// as `Host`. So requests must name the server as the user typed it, and WebSockets must
/// come from the server's own pages or from origins given with `--allow-origin`.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace mgrl::serve {

class OriginPolicy {
 public:
  /// The server listens on `listenHost` (an IP address as --host takes it) at `port`;
  /// `allowed` are the --allow-origin values, each `http://NAME[:PORT]` or
  /// `https://NAME[:PORT]`. Throws mgrl::Error naming the first malformed one.
  OriginPolicy(std::string_view listenHost, std::uint16_t port, const std::vector<std::string>& allowed);

  /// Why a request with this `Host` header is refused (nullopt: it is answered). An empty
  /// view is a missing header.
  std::optional<std::string> refuseHost(std::string_view host) const;
  /// Why a WebSocket upgrade with this `Origin` header is refused (nullopt: accepted).
  /// `present` false: no Origin header (not a browser; browsers always send one).
  std::optional<std::string> refuseOrigin(bool present, std::string_view origin) const;

  /// The hosts answered, for messages: "127.0.0.1:8080, localhost:8080, [::1]:8080".
  std::string hosts() const;

 private:
  struct Authority {
    std::string name;    ///< lower case; an IPv6 address keeps its brackets
    std::uint16_t port;  ///< as written, or the scheme's default
  };
  bool ownHost(const Authority& a) const;

  std::uint16_t port_;
  bool wildcard_;                    ///< listening on 0.0.0.0 or ::: any IP literal names this server
  std::vector<Authority> own_;       ///< the listening address and the loopback names, at port_
  std::vector<std::string> extra_;   ///< --allow-origin values, normalised
  std::vector<Authority> extraHosts_;
};

}  // namespace mgrl::serve
