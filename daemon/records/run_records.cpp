// SPDX-License-Identifier: Apache-2.0
#include "daemon/records/run_records.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstring>

#include "daemon/records/as_applied_reader.hpp"
#include "daemon/records/records_space.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

using namespace std::chrono_literals;

RunRecords::RunRecords(const Config& config, bool from_zero)
    : totals_file_(std::filesystem::path(config.daemon.state_dir) / "totals.toml") {
  std::string error;
  if (from_zero) {
    spdlog::info("simulation: totals start from zero in {} (--resume continues them)",
                 config.daemon.state_dir);
  } else {
    base_ = load_totals(totals_file_, &error);
  }
  if (!error.empty()) spdlog::warn("totals not restored: {}", error);
}

RunRecords::~RunRecords() = default;

void RunRecords::open_log(const Config& config) {
  log_ = std::make_unique<AsAppliedLog>(
      config.as_applied_dir(), static_cast<std::uintmax_t>(config.log.rotate_bytes),
      config.log.keep_files,
      NozzlePlacement{
          config.boom.nozzle_width_m,
          {config.gnss.antenna_ahead_of_nozzles_m, config.gnss.antenna_right_of_centre_m}});
  reconcile_with_log();
  persist();
}

void RunRecords::start_writer(Sprayer& sprayer, std::uint64_t floor_bytes,
                              std::chrono::milliseconds save_every) {
  sprayer_ = &sprayer;
  writer_ = std::jthread([this, floor_bytes, save_every](std::stop_token stop) {
    write_log(stop, floor_bytes, save_every);
  });
}

Totals RunRecords::totals() const {
  const ControlStatus control = sprayer_ != nullptr ? sprayer_->control() : ControlStatus{};
  Totals totals = base_;
  totals.area_m2 += control.area_m2;
  totals.volume_l += control.volume_l;
  totals.uniform_volume_l += control.uniform_volume_l;
  return totals;
}

// The log's records after the saved totals' mark, less what the totals already held of them,
// were sprayed after the last save (a crash or power cut: up to a minute): added back. The
// seq numbers run on after the log's last.
void RunRecords::reconcile_with_log() noexcept {
  const TotalsLogMark mark = base_.log;
  try {
    if (!mark.known) {
      log_->continue_after(last_as_applied_seq(log_->dir()));
      return;
    }
    const AsAppliedSummary after = read_as_applied_after(log_->dir(), mark.seq);
    log_->continue_after(std::max(after.last_seq, mark.seq));
    const double missing_l = after.volume_l - mark.queued_l;
    if (missing_l <= 0) return;
    base_.volume_l += missing_l;
    spdlog::info(
        "totals: {:.3f} L added from {} as-applied records (seq {}..{}) written after they "
        "were last saved",
        missing_l, after.records, after.first_seq, after.last_seq);
  } catch (const std::exception& error) {
    log_->continue_after(mark.seq);  // at least no seq the totals' mark names twice
    spdlog::warn("totals not reconciled with the as-applied log: {}", error.what());
  }
}

void RunRecords::persist() noexcept {
  try {
    // The log's progress first: records handed to it after this are not in its mark.
    const std::optional<AsAppliedProgress> logged =
        log_ ? std::optional(log_->progress()) : std::nullopt;
    Totals totals = this->totals();
    const double this_run_l = totals.volume_l - base_.volume_l;
    if (logged) totals.log = {true, logged->seq, std::max(0.0, this_run_l - logged->volume_l)};
    save_totals(totals_file_, totals);
  } catch (const std::exception& error) {
    spdlog::error("totals not saved: {}", error.what());
  }
}

// As-applied writer (normal priority): drains the control loop's queue; once a second writes
// the lines held while writes failed, fdatasyncs (a crash loses at most the last second) and
// judges the free space (records_disk_full, raised and cleared by the main loop); every
// `save_every` then saves the totals (persist() fsyncs them).
void RunRecords::write_log(std::stop_token stop, std::uint64_t floor_bytes,
                           std::chrono::milliseconds save_every) {
  auto last_flush = std::chrono::steady_clock::now();
  auto last_save = last_flush;
  bool reported = false;
  AsAppliedHealth seen;
  const auto drain = [&] {
    while (auto record = sprayer_->records().try_pop()) log_->write(*record);
  };
  const auto flush = [&] {
    log_->flush();
    const AsAppliedHealth health = log_->health();
    const std::optional<std::uint64_t> available = available_bytes(log_->dir());
    at_risk_.store(records_at_risk(health, available, floor_bytes));
    report_health(seen, health, available);
    seen = health;
  };
  // An exception must not end the process through std::terminate from this thread: log it
  // and keep draining (the control loop drops records only when the queue is full).
  const auto guarded = [&](auto&& step) {
    try {
      step();
    } catch (const std::exception& error) {
      if (!reported) spdlog::error("as-applied log: {}", error.what());
      reported = true;
    }
  };
  while (!stop.stop_requested()) {
    guarded(drain);
    const auto now = std::chrono::steady_clock::now();
    if (now - last_flush >= std::min<std::chrono::milliseconds>(1s, save_every)) {
      guarded(flush);
      last_flush = std::chrono::steady_clock::now();
    }
    if (now - last_save >= save_every) {
      persist();
      last_save = now;
    }
    std::this_thread::sleep_for(100ms);
  }
  guarded(drain);
  guarded(flush);
  if (seen.held_lines > 0)
    spdlog::error("as-applied log: {} lines not written at exit ({})", seen.held_lines,
                  std::strerror(seen.error));
}

// The journal lines for the as-applied log's changes since `seen`.
void RunRecords::report_health(const AsAppliedHealth& seen, const AsAppliedHealth& now,
                               std::optional<std::uint64_t> available) const {
  const std::string folder = log_->dir().string();
  if (now.error != 0 && seen.error == 0) {
    spdlog::error(
        "as-applied log: cannot write in {} ({}; {} MB free): lines wait in memory (up to "
        "{} MB) and are written once it works again",
        folder, std::strerror(now.error), available.value_or(0) / 1'000'000,
        kHeldLinesMaxBytes / 1'000'000);
  }
  if (now.dropped_lines != seen.dropped_lines) {
    spdlog::error(
        "as-applied log: {} lines dropped ({} in all), memory full: their seq numbers are "
        "missing from the file",
        now.dropped_lines - seen.dropped_lines, now.dropped_lines);
  }
  if (now.error == 0 && seen.error != 0) {
    spdlog::info("as-applied log: writing again in {} ({} lines dropped in all)", folder,
                 now.dropped_lines);
  }
}

}  // namespace weedspray::daemon
