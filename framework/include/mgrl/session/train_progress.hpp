#pragma once
/// \file
/// What training keeps around a learner (training.cpp): the progress shown to the user and
/// checkpoints on disk with their crash-test hooks. Not for other code: include
/// mgrl/session/training.hpp.
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mgrl/core/numbers.hpp"
#include "mgrl/learning/checkpoint_store.hpp"
#include "mgrl/learning/learner.hpp"
#include "mgrl/session/training.hpp"

namespace mgrl {

using Clock = std::chrono::steady_clock;

/// Where a behaviour's checkpoints go: `<out>.checkpoints/<behavior>` beside the bundle.
std::filesystem::path checkpointDirectory(const std::filesystem::path& out, const std::string& behavior);
/// After a finished run: a behaviour's checkpoint, what killed writers left beside it, and
/// the checkpoints folder once nothing else is in it.
void removeCheckpoint(const std::filesystem::path& dir);

// Progress of one behaviour's training: a bar redrawn in place on a terminal, else a line
// every 10 s through the log.
class ProgressReporter final : public TrainObserver {
 public:
  ProgressReporter(std::string name, bool bar, bool lines, WarningSink log, TrainListener* listener)
      : name_(std::move(name)),
        bar_(bar),
        lines_(lines),
        log_(std::move(log)),
        listener_(listener),
        start_(Clock::now()) {}
  ~ProgressReporter() override {
    if (drawn_) std::cerr << '\n';
  }

  std::size_t snapshotCount() const override { return listener_ ? listener_->snapshotCount() : 0; }
  void snapshot(const QTable& table, const CurvePoint& point, const Discretizer* grid) override {
    if (listener_) listener_->snapshot(table, point, grid);
  }

  void note(const std::string& text) override {
    if (drawn_) {
      std::cerr << '\n';
      drawn_ = false;
    }
    if (log_) log_(fmt::format("{}: {}", name_, text));
  }

  void progress(const TrainProgress& p) override {
    if (listener_) listener_->progress(p);
    if (!bar_ && !lines_) return;
    const double now = since(start_);
    const bool done = p.total > 0 && p.updates >= p.total;
    if (!done && now - last_ < (bar_ ? 0.2 : 10.0)) return;
    last_ = now;
    const double rate = p.seconds > 0 ? static_cast<double>(p.updates) / p.seconds : 0;
    // Before the first measurement there is no residual to show: say nothing of it.
    const std::string residual = p.residual < 0 ? std::string() : fmt::format("  residual {:.3g}", p.residual);
    std::string line;
    if (p.total > 0) {
      const double fraction = static_cast<double>(p.updates) / static_cast<double>(p.total);
      const double eta = rate > 0 ? static_cast<double>(p.total - p.updates) / rate : 0;
      constexpr int kWidth = 24;
      const int filled = static_cast<int>(fraction * kWidth);
      line = fmt::format("{} [{}{}] {:3.0f}%  {}updates/s{}  ETA {:.0f} s", name_, std::string(filled, '#'),
                         std::string(kWidth - filled, '.'), 100 * fraction, humanCount(rate), residual, eta);
    } else {
      line = fmt::format("{}: {}updates  {}updates/s{}", name_, humanCount(p.updates), humanCount(rate),
                         p.residual < 0 ? std::string() : fmt::format("  largest change {:.3g}", p.residual));
    }
    if (listener_) {
      const std::string status = listener_->status();
      if (!status.empty()) line += "  " + status;
    }
    if (bar_) {
      std::cerr << '\r' << line << "\x1b[K" << std::flush;
      drawn_ = true;
    } else if (log_) {
      log_(line);
    }
  }

 private:
  std::string name_;
  bool bar_, lines_;
  WarningSink log_;
  TrainListener* listener_;
  Clock::time_point start_;
  double last_ = -1e9;
  bool drawn_ = false;
};

// Checkpoints in a directory; MGRL_EXIT_AFTER_CHECKPOINTS=N makes the process exit at once
// after the N-th, as a kill would, so crash recovery can be tested without timing races.
// MGRL_STOP_AFTER_CHECKPOINTS=N raises the stop flag after the N-th, as a Ctrl-C would.
// A resumed run says where it resumed from.
class CrashTestCheckpointer final : public Checkpointer {
 public:
  CrashTestCheckpointer(DirectoryCheckpointer& inner, std::string behavior, WarningSink log, std::atomic<bool>* stop)
      : inner_(inner), behavior_(std::move(behavior)), log_(std::move(log)), stop_(stop) {
    if (const char* n = std::getenv("MGRL_EXIT_AFTER_CHECKPOINTS")) exitAfter_ = std::atoi(n);
    if (const char* n = std::getenv("MGRL_STOP_AFTER_CHECKPOINTS")) stopAfter_ = std::atoi(n);
  }
  void save(const nlohmann::json& state, const QTable& table) override {
    inner_.save(state, table);
    ++saved_;
    if (exitAfter_ > 0 && saved_ >= exitAfter_) {
      std::cerr << "mgrl: MGRL_EXIT_AFTER_CHECKPOINTS: exiting after checkpoint " << saved_ << '\n';
      std::_Exit(75);
    }
    if (stopAfter_ > 0 && saved_ == stopAfter_) stop_->store(true);
  }
  std::optional<nlohmann::json> load(QTable& table) override { return said(inner_.load(table)); }
  // The learner's own check of its state runs inside the directory checkpointer, which
  // reports a rejected state (naming state.json) and ignores the checkpoint.
  std::optional<nlohmann::json> loadChecked(QTable& table, const StateCheck& check) override {
    return said(inner_.loadChecked(table, check));
  }
  bool resumed() const { return resumed_; }

 private:
  std::optional<nlohmann::json> said(std::optional<nlohmann::json> state) {
    if (state && log_) {
      const nlohmann::json updates =
          state->is_object() && state->contains("updates") ? (*state)["updates"] : nlohmann::json();
      log_(fmt::format("resume: {}: continuing from the checkpoint{} in {}", behavior_,
                       updates.is_number_unsigned() ? fmt::format(" at {} actions", updates.get<std::uint64_t>()) : "",
                       inner_.directory().string()));
    }
    resumed_ = state.has_value();
    return state;
  }

  DirectoryCheckpointer& inner_;
  std::string behavior_;
  WarningSink log_;
  std::atomic<bool>* stop_;
  int exitAfter_ = 0, stopAfter_ = 0, saved_ = 0;
  bool resumed_ = false;
};

}  // namespace mgrl
