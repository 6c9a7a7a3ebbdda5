#include "serve/server.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <deque>
#include <optional>

#include <boost/asio.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <fmt/format.h>

#include "serve/static_files.hpp"

namespace mgrl::serve {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace fs = std::filesystem;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

constexpr std::size_t kHeaderLimit = 8 * 1024;
constexpr auto kIdle = std::chrono::seconds(30);
constexpr std::size_t kMaxQueuedMessages = 4096;  ///< text messages waiting for a slow page
constexpr double kStatsEvery_s = 0.5;

}  // namespace

// What connections share. Owned jointly by the server and every connection, so that the
// connections the io_context destroys when it goes can still count themselves out.
struct Shared {
  std::shared_ptr<const ViewerAssets> assets;
  ServerOptions options;
  fs::path root;
  std::atomic<int> sessions{0};

  void log(const std::string& line) const {
    if (options.log) options.log(line);
  }
};

struct Server::Impl {
  std::shared_ptr<Shared> shared = std::make_shared<Shared>();
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  std::optional<net::signal_set> signals;

  void accept();
};

namespace {

// One page's WebSocket: reads its messages, ticks its world, writes its frames.
class PageSession : public std::enable_shared_from_this<PageSession> {
 public:
  PageSession(tcp::socket socket, std::shared_ptr<Shared> server)
      : ws_(std::move(socket)), server_(*server), keep_(std::move(server)), timer_(ws_.get_executor()),
        viewer_(server_.assets) {
    ++server_.sessions;
  }
  ~PageSession() { --server_.sessions; }

  void start(http::request<http::empty_body> request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(Limits::kMessageBytes);
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->server_.log(fmt::format("serve: a page connected ({} open)", self->server_.sessions.load()));
      self->period_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(self->viewer_.frameTime()));
      self->nextTick_ = Clock::now();
      self->nextStats_ = Clock::now();
      self->flushOutbox();
      self->read();
      self->tick();
    });
  }

 private:
  struct Outgoing {
    bool binary = false;
    std::string text;
    std::vector<std::uint8_t> bytes;
  };

  void read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->onRead(ec); });
  }

  void onRead(beast::error_code ec) {
    if (ec) {  // closed, timed out, too big (Beast closes with 1009) or broken
      finish();
      return;
    }
    try {
      if (!ws_.got_text()) {
        close(websocket::close_code::unknown_data, "expected text messages (JSON), found a binary message");
        return;
      }
      const auto now = Clock::now();
      if (now - windowStart_ >= std::chrono::seconds(1)) {
        windowStart_ = now;
        windowCount_ = 0;
      }
      if (++windowCount_ > Limits::kMessagesPerSecond) {
        close(websocket::close_code::policy_error,
              fmt::format("expected at most {} messages per second", Limits::kMessagesPerSecond));
        return;
      }
      const std::string text = beast::buffers_to_string(buffer_.data());
      buffer_.consume(buffer_.size());
      viewer_.handle(text);
      dirty_ = true;
      flushOutbox();
    } catch (const std::exception& e) {
      server_.log(fmt::format("serve: a page's message failed: {}", e.what()));
      close(websocket::close_code::internal_error, "internal error");
      return;
    }
    read();
  }

  void tick() {
    timer_.expires_at(nextTick_);
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->onTick();
    });
  }

  void onTick() {
    if (closing_) return;
    try {
      const bool moved = viewer_.advance(1.0);
      if (moved || dirty_) {
        dirty_ = false;
        if (binaryPending_) {
          ++framesDropped_;
        } else {
          const auto& frame = viewer_.frame();
          queue_.push_back({true, {}, frame});
          binaryPending_ = true;
          ++framesSent_;
        }
      }
      const auto now = Clock::now();
      if (now >= nextStats_) {
        nextStats_ = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kStatsEvery_s));
        queue_.push_back({false, viewer_.stats(framesSent_, framesDropped_), {}});
      }
      flushOutbox();
      nextTick_ += period_;
      if (nextTick_ < now - 5 * period_) nextTick_ = now + period_;  // behind: skip, do not race
    } catch (const std::exception& e) {
      server_.log(fmt::format("serve: a page's world failed: {}", e.what()));
      close(websocket::close_code::internal_error, "internal error");
      return;
    }
    tick();
  }

  void flushOutbox() {
    for (std::string& text : viewer_.takeOutbox()) queue_.push_back({false, std::move(text), {}});
    if (queue_.size() > kMaxQueuedMessages) {
      queue_.clear();
      binaryPending_ = false;
      close(websocket::close_code::policy_error, "the page reads too slowly");
      return;
    }
    write();
  }

  void write() {
    if (writing_) return;
    if (closeCode_) {
      if (closing_) return;
      closing_ = true;
      timer_.cancel();
      ws_.async_close(websocket::close_reason(*closeCode_, closeReason_),
                      [self = shared_from_this()](beast::error_code) {});
      return;
    }
    if (queue_.empty()) return;
    writing_ = true;
    Outgoing& front = queue_.front();
    ws_.binary(front.binary);
    auto done = [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->writing_ = false;
      if (self->queue_.empty()) return;
      if (self->queue_.front().binary) self->binaryPending_ = false;
      self->queue_.pop_front();
      if (ec) {
        self->finish();
        return;
      }
      self->write();
    };
    if (front.binary)
      ws_.async_write(net::buffer(front.bytes), std::move(done));
    else
      ws_.async_write(net::buffer(front.text), std::move(done));
  }

  // Closes with a code the page sees (after any write in flight).
  void close(websocket::close_code code, std::string reason) {
    if (closeCode_) return;
    closeCode_ = code;
    closeReason_ = std::move(reason);
    queue_.clear();
    write();
  }

  // The connection is gone: stop ticking; the last handler releases the session.
  void finish() {
    if (!finished_) server_.log(fmt::format("serve: a page left ({} open)", server_.sessions.load() - 1));
    finished_ = true;
    closing_ = true;
    timer_.cancel();
  }

  websocket::stream<beast::tcp_stream> ws_;
  Shared& server_;
  std::shared_ptr<Shared> keep_;
  net::steady_timer timer_;
  ViewerSession viewer_;
  beast::flat_buffer buffer_;
  std::deque<Outgoing> queue_;
  bool writing_ = false, binaryPending_ = false, dirty_ = true, closing_ = false, finished_ = false;
  std::optional<websocket::close_code> closeCode_;
  std::string closeReason_;
  Clock::duration period_{};
  Clock::time_point nextTick_, nextStats_, windowStart_{};
  int windowCount_ = 0;
  std::size_t framesSent_ = 0, framesDropped_ = 0;
};

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
    if (websocket::is_upgrade(request)) {
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
      std::make_shared<PageSession>(stream_.release_socket(), server_)->start(std::move(request));
      return;
    }
    if (request.method() != http::verb::get && request.method() != http::verb::head) {
      sendText(http::status::method_not_allowed, "expected GET or HEAD\n", request.version(), request.keep_alive());
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

  void sendText(http::status status, std::string text, unsigned version, bool keepAlive) {
    http::response<http::string_body> response{status, version};
    headers(response, "text/plain; charset=utf-8", keepAlive);
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
    if (!ec) std::make_shared<HttpConnection>(std::move(socket), shared)->read();
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
  impl.accept();
}

Server::~Server() = default;

std::uint16_t Server::port() const { return impl_->acceptor.local_endpoint().port(); }

void Server::run() { impl_->ioc.run(); }

void Server::stop() {
  net::post(impl_->ioc, [impl = impl_.get()] {
    beast::error_code ec;
    impl->acceptor.close(ec);
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
