#include "serve/server.hpp"

#include <csignal>

#include "serve/connection.hpp"
#include "serve/static_files.hpp"

namespace mgrl::serve {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kHeaderLimit = 8 * 1024;
constexpr auto kIdle = std::chrono::seconds(30);
/// accept() failing for want of descriptors or memory: retried after this, doubling.
constexpr auto kAcceptRetryFirst = std::chrono::milliseconds(50);
constexpr auto kAcceptRetryMax = std::chrono::seconds(1);

}  // namespace

struct Server::Impl {
  std::shared_ptr<Shared> shared = std::make_shared<Shared>();
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  std::optional<net::signal_set> signals;
  net::steady_timer acceptRetry{ioc};
  Clock::duration acceptDelay{};  ///< zero: accepting; else the back-off in force

  void accept();
  void pauseAccepting(const beast::error_code& ec);
};

namespace {

// One HTTP connection: static files, or the upgrade to a PageSession.
class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(tcp::socket socket, std::shared_ptr<Shared> server) : stream_(std::move(socket)), server_(std::move(server)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(kHeaderLimit);
    parser_->body_limit(0);
    stream_.expires_after(kIdle);
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onRead(ec); });
  }

 private:
  void onRead(beast::error_code ec) {
    if (ec == http::error::end_of_stream || ec == beast::error::timeout || ec == net::error::operation_aborted ||
        ec == net::error::connection_reset || ec == net::error::eof) {
      shutdown();
      return;
    }
    if (ec) {  // malformed, headers too long, a body where none may be
      sendText(http::status::bad_request, fmt::format("bad request: {}\n", ec.message()), 11, false);
      return;
    }
    http::request<http::empty_body> request = parser_->release();
    // One Host (RFC 9112 sec. 3.2: a request with more is answered 400) and at most one
    // Origin: with two, which one a check reads and which one a proxy or the page meant
    // may differ.
    for (const auto field : {http::field::host, http::field::origin})
      if (const std::size_t n = request.count(field); n > 1) {
        const std::string why = fmt::format("expected one {} header, found {}", http::to_string(field), n);
        server_->refused(why);
        sendText(http::status::bad_request, why + "\n", request.version(), false);
        return;
      }
    // Who may ask (serve/origin.hpp): requests that name this server, pages of its origins.
    const auto host = request.find(http::field::host);
    if (const auto why = server_->origins->refuseHost(host == request.end() ? std::string_view() : host->value())) {
      server_->refused(*why);
      sendText(host == request.end() ? http::status::bad_request : http::status::misdirected_request, *why + "\n",
               request.version(), false);
      return;
    }
    if (websocket::is_upgrade(request)) {
      const auto origin = request.find(http::field::origin);
      if (const auto why =
              server_->origins->refuseOrigin(origin != request.end(), origin == request.end() ? "" : origin->value())) {
        server_->refused(*why);
        sendText(http::status::forbidden, *why + "\n", request.version(), false);
        return;
      }
      if (request.target() != "/ws") {
        sendText(http::status::not_found, "WebSocket: expected the path /ws\n", request.version(), false);
        return;
      }
      if (server_->sessions.load() >= server_->options.maxSessions) {
        sendText(http::status::service_unavailable,
                 fmt::format("expected at most {} pages at once; close one\n", server_->options.maxSessions),
                 request.version(), false);
        return;
      }
      stream_.expires_never();  // the WebSocket has its own timeouts
      startPageSession(stream_.release_socket(), server_, request);
      return;
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      sendText(http::status::method_not_allowed, "expected GET or HEAD\n", request.version(), request.keep_alive(),
               "GET, HEAD");
      return;
    }
    const StaticLookup found = lookupStatic(server_->root, request.target());
    if (found.status != 200) {
      sendText(static_cast<http::status>(found.status), found.reason + "\n", request.version(), request.keep_alive());
      return;
    }
    http::file_body::value_type body;
    body.open(found.file.c_str(), beast::file_mode::scan, ec);
    if (ec) {
      sendText(http::status::not_found, "no such file\n", request.version(), request.keep_alive());
      return;
    }
    const auto size = body.size();
    if (request.method() == http::verb::head) {
      http::response<http::empty_body> response{http::status::ok, request.version()};
      headers(response, mimeType(found.file), request.keep_alive());
      response.content_length(size);
      send(std::move(response));
      return;
    }
    http::response<http::file_body> response{std::piecewise_construct, std::make_tuple(std::move(body)),
                                             std::make_tuple(http::status::ok, request.version())};
    headers(response, mimeType(found.file), request.keep_alive());
    response.content_length(size);
    send(std::move(response));
  }

  template <class Body>
  static void headers(http::response<Body>& response, std::string_view type, bool keepAlive) {
    response.set(http::field::server, "mgrl");
    response.set(http::field::content_type, type);
    response.set(http::field::cache_control, "no-store");
    response.keep_alive(keepAlive);
  }

  // `allow`: the methods a 405 names (RFC 9110 sec. 15.5.6 requires the Allow header).
  void sendText(http::status status, std::string text, unsigned version, bool keepAlive, std::string_view allow = {}) {
    http::response<http::string_body> response{status, version};
    headers(response, "text/plain; charset=utf-8", keepAlive);
    if (!allow.empty()) response.set(http::field::allow, allow);
    response.body() = std::move(text);
    response.prepare_payload();
    send(std::move(response));
  }

  template <class Body>
  void send(http::response<Body>&& response) {
    auto kept = std::make_shared<http::response<Body>>(std::move(response));
    http::async_write(stream_, *kept, [self = shared_from_this(), kept](beast::error_code ec, std::size_t) {
      if (ec || kept->need_eof()) {
        self->shutdown();
        return;
      }
      self->read();
    });
  }

  void shutdown() {
    beast::error_code ec;
    stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
  }

  beast::tcp_stream stream_;
  std::shared_ptr<Shared> server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::empty_body>> parser_;
};

}  // namespace

void Server::Impl::accept() {
  acceptor.async_accept(ioc, [this](beast::error_code ec, tcp::socket socket) {
    if (ec == net::error::operation_aborted || !acceptor.is_open()) return;
    if (ec) {
      pauseAccepting(ec);
      return;
    }
    if (acceptDelay != Clock::duration::zero()) {
      shared->log("serve: accepting connections again");
      acceptDelay = Clock::duration::zero();
    }
    std::make_shared<HttpConnection>(std::move(socket), shared)->read();
    accept();
  });
}

// accept() failed: out of descriptors (EMFILE, ENFILE), of memory, or a connection reset
// before it was taken. Accepting again at once would fail again at once (the connection
// stays queued) and spin a core; so wait, doubling the wait up to a second, until a
// descriptor frees. Said once per episode, not once per try.
void Server::Impl::pauseAccepting(const beast::error_code& ec) {
  if (ec == net::error::connection_aborted) {  // that client is gone; nothing is short
    accept();
    return;
  }
  if (acceptDelay == Clock::duration::zero()) {
    shared->log(fmt::format("serve: cannot accept connections ({}); pausing and retrying every {} ms to {} s until it "
                            "can (open pages keep running)",
                            ec.message(), std::chrono::duration_cast<std::chrono::milliseconds>(kAcceptRetryFirst).count(),
                            std::chrono::duration_cast<std::chrono::seconds>(kAcceptRetryMax).count()));
    acceptDelay = kAcceptRetryFirst;
  } else {
    acceptDelay = std::min<Clock::duration>(2 * acceptDelay, kAcceptRetryMax);
  }
  acceptRetry.expires_after(acceptDelay);
  acceptRetry.async_wait([this](beast::error_code waited) {
    if (waited || !acceptor.is_open()) return;
    accept();
  });
}

Server::Server(std::shared_ptr<const ViewerAssets> assets, ServerOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& impl = *impl_;
  Shared& shared = *impl.shared;
  shared.assets = std::move(assets);
  shared.options = std::move(options);
  const ServerOptions& o = shared.options;
  std::error_code fsError;
  shared.root = fs::canonical(o.webRoot, fsError);
  if (fsError || !fs::is_regular_file(shared.root / "index.html"))
    throw Error(fmt::format("--web {}: expected the viewer's folder with index.html, found {}",
                            o.webRoot.string(), fsError ? fsError.message() : "no index.html"));
  if (!fs::is_regular_file(shared.root / "node_modules/three/build/three.module.js"))
    throw Error(fmt::format("--web {}: expected three.js in node_modules/three (installed by scripts/setup.sh), found "
                            "none: run `npm ci --prefix {}`",
                            o.webRoot.string(), o.webRoot.string()));
  beast::error_code ec;
  const auto address = net::ip::make_address(o.host, ec);
  if (ec) throw Error(fmt::format("--host: expected an IP address, found {}", o.host));
  const tcp::endpoint endpoint(address, o.port);
  auto failed = [&](const char* what) {
    return Error(fmt::format("--port {}: cannot {} {}:{}: {}", o.port, what, o.host,
                             o.port, ec.message()));
  };
  impl.acceptor.open(endpoint.protocol(), ec);
  if (ec) throw failed("open a socket for");
  impl.acceptor.set_option(net::socket_base::reuse_address(true), ec);
  impl.acceptor.bind(endpoint, ec);
  if (ec) throw failed("listen on");
  impl.acceptor.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw failed("listen on");
  shared.origins.emplace(o.host, impl.acceptor.local_endpoint().port(), o.allowOrigins);
  shared.log(fmt::format("serve: answering requests for {} only; WebSocket pages of other origins are refused "
                         "(--allow-origin adds one)",
                         shared.origins->hosts()));
  impl.accept();
}

Server::~Server() {
  impl_.reset();          // the pages go, each asking its retraining (if any) to stop
  waitForWorkers();       // none outlives the server
}

std::uint16_t Server::port() const { return impl_->acceptor.local_endpoint().port(); }

void Server::run() { impl_->ioc.run(); }

void Server::stop() {
  net::post(impl_->ioc, [impl = impl_.get()] {
    beast::error_code ec;
    impl->acceptor.close(ec);
    impl->acceptRetry.cancel();
    impl->ioc.stop();
  });
}

void Server::stopOnSignals() {
  impl_->signals.emplace(impl_->ioc, SIGINT, SIGTERM);
  impl_->signals->async_wait([impl = impl_.get()](beast::error_code ec, int) {
    if (ec) return;
    beast::error_code ignored;
    impl->acceptor.close(ignored);
    impl->ioc.stop();
  });
}

int Server::sessions() const { return impl_->shared->sessions.load(); }

}  // namespace mgrl::serve
