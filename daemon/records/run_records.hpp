// SPDX-License-Identifier: Apache-2.0
// The run's records: the totals kept across restarts (<state_dir>/totals.toml), in step with the
// as-applied log, and the writer thread that drains the control loop's records into that log.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stop_token>
#include <thread>

#include "daemon/config/config.hpp"
#include "daemon/records/as_applied_log.hpp"
#include "daemon/records/totals.hpp"

namespace weedspray::daemon {

class Sprayer;

class RunRecords {
 public:
  // Loads the saved totals (`from_zero`: a fresh simulation, which --resume continues instead).
  // The state folder must exist.
  RunRecords(const Config& config, bool from_zero);
  ~RunRecords();
  RunRecords(const RunRecords&) = delete;
  RunRecords& operator=(const RunRecords&) = delete;

  // Opens the as-applied log, adds back what it holds past the saved totals' mark, and saves a
  // first mark (a crash in the first minute is then matched).
  void open_log(const Config& config);
  // The writer thread, draining `sprayer`'s records until stop_writer(); `sprayer` also gives
  // this run's totals from then on. The writer saves the totals every `save_every`, after the
  // log's flush: their fsync never holds up the main loop, and the mark they save names
  // records already on disk.
  void start_writer(Sprayer& sprayer, std::uint64_t floor_bytes,
                    std::chrono::milliseconds save_every = kSaveEvery);
  static constexpr std::chrono::milliseconds kSaveEvery{60'000};
  // Joins the writer after it drained the queue and flushed.
  void stop_writer() noexcept { writer_ = {}; }

  // The saved totals plus this run's so far.
  Totals totals() const;
  // Saves the totals with the log's mark; an error is logged. The writer does it while it runs;
  // before start_writer() and after stop_writer() the caller may.
  void persist() noexcept;
  // The free space or a failing write puts the records at risk (records_disk_full).
  bool at_risk() const noexcept { return at_risk_.load(); }
  const std::filesystem::path& log_dir() const { return log_->dir(); }

 private:
  void reconcile_with_log() noexcept;
  void write_log(std::stop_token stop, std::uint64_t floor_bytes,
                 std::chrono::milliseconds save_every);
  void report_health(const AsAppliedHealth& seen, const AsAppliedHealth& now,
                     std::optional<std::uint64_t> available) const;

  std::filesystem::path totals_file_;
  Totals base_;
  Sprayer* sprayer_ = nullptr;  // from start_writer() on
  std::unique_ptr<AsAppliedLog> log_;
  std::atomic<bool> at_risk_{false};  // from the writer thread
  std::jthread writer_;               // last: joined before the log goes
};

}  // namespace weedspray::daemon
