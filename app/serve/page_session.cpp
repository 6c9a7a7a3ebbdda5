// One page's WebSocket (docs/viewer-protocol.md): its messages read, its world ticked
// within its share of the network thread, its frames queued and written, its close.
#include <algorithm>
#include <chrono>
#include <deque>

#include <malloc.h>

#include "serve/connection.hpp"

namespace mgrl::serve {

namespace {

constexpr std::size_t kMaxQueuedMessages = 4096;  ///< messages waiting for a slow page
/// Bytes waiting for a slow page (its pose frame included): the bound on what a page that
/// does not read costs the server (docs/viewer-protocol.md, "Limits").
constexpr std::size_t kMaxQueuedBytes = 8u << 20;
constexpr double kStatsEvery_s = 0.5;
/// A page being closed that has not taken its close frame by then is dropped.
constexpr auto kCloseDeadline = std::chrono::seconds(10);
/// The one network thread's time that the pages' worlds share (simulating, encoding and
/// handling messages), as a fraction of wall time: each page may use this divided by the
/// pages open, so that a light page keeps its frames whatever the others ask. The rest is
/// the sockets'. Unused share is not lent: a heavy page is slowed even beside idle ones.
constexpr double kWorldShare = 0.5;
/// How far ahead of its share a page may run, s (a burst: a mode change, a retraining's
/// table taken).
constexpr double kAllowanceMax = 0.1;
/// A message that costs the network thread this long or longer is costly: a mode or crowd
/// switch, a lesson's start. Costly messages of all pages take turns (Shared::costlyFree).
constexpr double kCostly = 0.01;
/// The longest a page's world simulates in one tick before the frames still due are
/// dropped: a crowd's eight frames (speed 4, a late timer) took 110 ms here, and far longer
/// on a loaded machine, holding every other page for that long.
constexpr double kStepSlice = 0.02;

// glibc keeps freed memory in its arenas; a page that leaves may have held megabytes
// (a crowd's frames, a retrained table), so hand what is free at the top back to the
// system when one goes.
struct TrimOnExit {
  ~TrimOnExit() { ::malloc_trim(0); }
};

// One page's WebSocket: reads its messages, ticks its world, writes its frames.
class PageSession : public std::enable_shared_from_this<PageSession> {
 public:
  PageSession(tcp::socket socket, std::shared_ptr<Shared> server)
      : trim_(),
        ws_(std::move(socket)),
        server_(*server),
        keep_(std::move(server)),
        timer_(ws_.get_executor()),
        viewer_(server_.assets) {
    ++server_.sessions;
    viewer_.buildInBackground(true);
  }
  ~PageSession() {
    if (!finished_) --server_.sessions;
  }

  void start(const http::request<http::empty_body>& request) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(Limits::kMessageBytes);
    // RFC 6455 sec. 7.4.2 defines close codes up to 4999; Beast takes 5000-65535 too and
    // would echo them. Such a close fails the connection instead: the socket is shut down
    // before the echo is written.
    ws_.control_callback([this](websocket::frame_type kind, beast::string_view) {
      if (kind != websocket::frame_type::close || ws_.reason().code < 5000) return;
      server_.log(
          fmt::format("serve: a page closed with code {}, which RFC 6455 does not define (expected 1000-4999); "
                      "dropping its connection without an echo",
                      static_cast<unsigned>(ws_.reason().code)));
      beast::error_code ignored;
      beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
    });
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) {
      if (ec) return;
      self->server_.log(fmt::format("serve: a page connected ({} open)", self->server_.sessions.load()));
      self->period_ =
          std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(self->viewer_.frameTime()));
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
    std::size_t size() const { return binary ? bytes.size() : text.size(); }
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
      if (closeCode_) {  // closing: read on (for the page's close), act on nothing
        buffer_.consume(buffer_.size());
        read();
        return;
      }
      pending_ = beast::buffers_to_string(buffer_.data());
      buffer_.consume(buffer_.size());
      pendingSince_ = now;
    } catch (const std::exception& e) {
      server_.log(fmt::format("serve: a page's message failed: {}", e.what()));
      close(websocket::close_code::internal_error, "internal error");
      return;
    }
    process();
  }

  // Handles the message read (pending_) if this page's share covers its price and no other
  // page's costly message has just run, then reads the next; else leaves it waiting, and
  // the page's socket unread, for a later tick to try again. So a page's messages cost it
  // as its world's steps do: one that spends more than its share waits, and its kernel
  // buffers, then its own sending, hold the rest (docs/viewer-protocol.md, "Limits and
  // fairness").
  void process() {
    try {
      const auto now = Clock::now();
      refill(now);
      const double price = std::min(viewer_.price(pending_), kAllowanceMax);
      const bool costly = price >= kCostly;
      if (!viewer_.ready(pending_) || allowance_ < std::max(price, 0.0) || (costly && now < server_.costlyFree)) {
        if (!waiting_) ++messagesWaited_;
        waiting_ = true;
        return;
      }
      if (waiting_) {
        waiting_ = false;
        waitedSeconds_ += std::chrono::duration<double>(now - pendingSince_).count();
        // The page's messages sat in the socket while this one waited: they are counted
        // against the rate limit from now, as they are read, not for when they arrived.
        windowStart_ = now;
        windowCount_ = 1;
      }
      viewer_.handle(pending_);
      pending_.clear();
      const auto ended = Clock::now();
      spend(now);
      took(now, ended, costly);
      dirty_ = true;
      flushOutbox();
    } catch (const std::exception& e) {
      server_.log(fmt::format("serve: a page's message failed: {}", e.what()));
      close(websocket::close_code::internal_error, "internal error");
      return;
    }
    if (!closeCode_) read();
  }

  void tick() {
    timer_.expires_at(nextTick_);
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (!ec) self->onTick();
    });
  }

  // This page's share of the network thread (kWorldShare over the pages open), as an
  // allowance of seconds refilled with time and spent by its world.
  double share() const { return kWorldShare / std::max(1, server_.sessions.load()); }
  void refill(Clock::time_point now) {
    allowance_ = std::min(kAllowanceMax, allowance_ + share() * std::chrono::duration<double>(now - refilled_).count());
    refilled_ = now;
  }
  void spend(Clock::time_point began) {
    const auto now = Clock::now();
    refill(now);
    allowance_ -= std::chrono::duration<double>(now - began).count();
  }

  // Costly work of the pages takes turns with everything else on the thread: after a
  // costly message, a world installed or a crowd's step (`costly`: priced as such before it
  // ran, or it took kCostly or longer), no other costly work starts for as long as it took.
  void took(Clock::time_point began, Clock::time_point ended, bool costly) {
    if (costly || ended - began >= std::chrono::duration<double>(kCostly))
      server_.costlyFree = std::max(server_.costlyFree, ended + (ended - began));
  }

  void onTick() {
    if (closing_ || closeCode_) return;
    try {
      // A world built in the background: installed (its first frame run) on this thread,
      // in its turn with the other costly work; its first step is taken to cost as much.
      const auto began = Clock::now();
      if (began >= server_.costlyFree && viewer_.poll()) {
        refill(began);
        spend(began);
        const auto installed = Clock::now();
        lastStep_ = std::chrono::duration<double>(installed - began).count();
        took(began, installed, false);
        dirty_ = true;
        flushOutbox();
        if (closeCode_) return;
      }
    } catch (const std::exception& e) {
      server_.log(fmt::format("serve: a page's world failed: {}", e.what()));
      close(websocket::close_code::internal_error, "internal error");
      return;
    }
    if (waiting_) {
      process();
      if (closeCode_) return;
    }
    try {
      const auto began = Clock::now();
      refill(began);
      ++ticks_;
      // Over its share: this step is skipped (its world runs slower), and `stats` says why.
      // A message waiting for its price goes first: the world holds still until it has run.
      // A world whose steps are costly (a crowd) takes turns with the other costly work.
      const bool turn = lastStep_ < kCostly || began >= server_.costlyFree;
      const bool over = allowance_ < 0 || waiting_ || !turn;
      if (over && !waiting_) ++ticksSkipped_;  // held for a message: its stats say so
      const bool moved = !over && viewer_.advance(1.0, kStepSlice);
      if (moved || (dirty_ && !over)) {
        dirty_ = false;
        if (binaryPending_) {
          ++framesDropped_;
        } else {
          const auto& frame = viewer_.frame();
          push({true, {}, frame});
          binaryPending_ = true;
          ++framesSent_;
        }
      }
      if (!over) {
        spend(began);
        const auto stepped = Clock::now();
        lastStep_ = std::chrono::duration<double>(stepped - began).count();
        took(began, stepped, false);
      }
      const auto now = Clock::now();
      if (now >= nextStats_) {
        nextStats_ = now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(kStatsEvery_s));
        double waited = waitedSeconds_;
        if (waiting_) waited += std::chrono::duration<double>(now - pendingSince_).count();
        const PageShare fair{share(), server_.sessions.load(), ticksSkipped_, ticks_, messagesWaited_, waited};
        push({false, viewer_.stats(framesSent_, framesDropped_, fair), {}});
        ticks_ = ticksSkipped_ = 0;
        messagesWaited_ = 0;
        waitedSeconds_ = 0;
        if (waiting_) {  // what it has waited is said; the next stats count on from now
          pendingSince_ = now;
          messagesWaited_ = 1;
        }
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

  void push(Outgoing message) {
    queuedBytes_ += message.size();
    queue_.push_back(std::move(message));
  }

  void flushOutbox() {
    if (closeCode_) {  // closing: what the world says now is for nobody
      (void)viewer_.takeOutbox();
      write();
      return;
    }
    for (std::string& text : viewer_.takeOutbox()) push({false, std::move(text), {}});
    if (queue_.size() > kMaxQueuedMessages || queuedBytes_ > kMaxQueuedBytes) {
      server_.log(fmt::format("serve: closing a page that reads too slowly ({} messages, {} bytes waiting)",
                              queue_.size(), queuedBytes_));
      clearQueue();
      close(websocket::close_code::policy_error,
            fmt::format("the page reads too slowly: expected at most {} messages or {} MiB waiting to be sent",
                        kMaxQueuedMessages, kMaxQueuedBytes >> 20));
      return;
    }
    write();
  }

  // Drops what waits (not a write in flight, whose buffer Beast is reading) and gives the
  // memory back.
  void clearQueue() {
    std::deque<Outgoing> kept;
    if (writing_ && !queue_.empty()) kept.push_back(std::move(queue_.front()));
    queue_.swap(kept);
    queuedBytes_ = queue_.empty() ? 0 : queue_.front().size();
    binaryPending_ = !queue_.empty() && queue_.front().binary;
  }

  void write() {
    if (writing_) return;
    if (closeCode_) {
      if (closing_) return;
      closing_ = true;  // the timer now holds close()'s deadline, no tick
      ws_.async_close(websocket::close_reason(*closeCode_, closeReason_),
                      [self = shared_from_this()](beast::error_code) { self->finish(); });
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
      self->queuedBytes_ -= self->queue_.front().size();
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
  // From then on the page's messages are ignored and its world stops. A page that does
  // not read may never finish the write in flight, so the socket is shut down if the close
  // has not gone out within kCloseDeadline.
  void close(websocket::close_code code, std::string reason) {
    if (closeCode_) return;
    closeCode_ = code;
    closeReason_ = std::move(reason);
    clearQueue();
    timer_.expires_after(kCloseDeadline);  // replaces the next tick
    timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || self->finished_) return;
      self->server_.log("serve: a closing page did not take its close in time; dropping its connection");
      beast::error_code ignored;
      beast::get_lowest_layer(self->ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
    });
    write();
  }

  // The connection is gone: stop ticking; the last handler releases the session. The page
  // is counted out now, not when its last handler lets go, so that pages leaving together
  // each say how many stay.
  void finish() {
    if (!finished_) server_.log(fmt::format("serve: a page left ({} open)", --server_.sessions));
    finished_ = true;
    closing_ = true;
    timer_.cancel();
  }

  TrimOnExit trim_;  // first: runs after every other member is gone
  websocket::stream<beast::tcp_stream> ws_;
  Shared& server_;
  std::shared_ptr<Shared> keep_;
  net::steady_timer timer_;
  ViewerSession viewer_;
  beast::flat_buffer buffer_;
  std::deque<Outgoing> queue_;
  std::size_t queuedBytes_ = 0;
  bool writing_ = false, binaryPending_ = false, dirty_ = true, closing_ = false, finished_ = false;
  std::optional<websocket::close_code> closeCode_;
  std::string closeReason_;
  Clock::duration period_{};
  Clock::time_point nextTick_, nextStats_, windowStart_{};
  int windowCount_ = 0;
  std::string pending_;             ///< the message read and not yet handled
  bool waiting_ = false;            ///< pending_ waits for the page's share or its turn
  Clock::time_point pendingSince_;  ///< since when pending_ waits (or the last stats)
  std::size_t messagesWaited_ = 0;  ///< since the last stats
  double waitedSeconds_ = 0;        ///< by them, in all
  std::size_t framesSent_ = 0, framesDropped_ = 0;
  double lastStep_ = 0;               ///< s, the last step of the world (simulating and encoding)
  double allowance_ = kAllowanceMax;  ///< seconds of the network thread this page may still use
  Clock::time_point refilled_ = Clock::now();
  std::size_t ticks_ = 0, ticksSkipped_ = 0;  ///< since the last stats
};

}  // namespace

void startPageSession(tcp::socket socket, std::shared_ptr<Shared> server,
                      const http::request<http::empty_body>& request) {
  std::make_shared<PageSession>(std::move(socket), std::move(server))->start(request);
}

}  // namespace mgrl::serve
