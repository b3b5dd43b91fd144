// SPDX-License-Identifier: Apache-2.0
#include "io/analog_io_worker.hpp"

#include <algorithm>

namespace weedspray::io {

using std::chrono::nanoseconds;

AnalogIoWorker::AnalogIoWorker(AnalogInput& adc, AnalogOutput& dac, Clock& clock,
                               AnalogIoTiming timing) noexcept
    : adc_(adc), dac_(dac), clock_(clock), timing_(timing) {}

nanoseconds AnalogIoWorker::lead_for(nanoseconds read_time_estimate) const noexcept {
  const nanoseconds wanted = read_time_estimate * 3 / 2 + timing_.min_lead;
  return std::clamp(wanted, timing_.min_lead, std::max(timing_.min_lead, timing_.period / 2));
}

void AnalogIoWorker::run(std::stop_token stop, nanoseconds first_deadline) noexcept {
  AnalogIoStats stats;
  nanoseconds read_time_estimate{0};
  DacCommand written;
  bool have_written = false;
  nanoseconds deadline = first_deadline;
  while (!stop.stop_requested()) {
    stats.lead = lead_for(read_time_estimate);
    clock_.sleep_until(deadline - stats.lead);
    if (stop.stop_requested()) break;

    const nanoseconds read_started = clock_.now();
    sample_.publish(adc_.read());
    const nanoseconds read_time = clock_.now() - read_started;
    ++stats.reads;
    stats.max_read_time = std::max(stats.max_read_time, read_time);
    // A decaying maximum (-5 % a cycle): one slow read widens the lead for a few dozen cycles,
    // not for the rest of the run.
    read_time_estimate = std::max(read_time, read_time_estimate - read_time_estimate / 20);

    clock_.sleep_until(deadline + timing_.lag);
    write_pending(written, have_written);
    stats.writes = writes_;
    stats.dac_errors = dac_.error_count();
    stats.dac_faults = dac_faults_;
    stats.dac_tolerated = dac_tolerated_;

    // The next deadline whose read slot is still ahead; slots already past are overruns.
    deadline += timing_.period;
    const nanoseconds now = clock_.now();
    const nanoseconds next_read = deadline - lead_for(read_time_estimate);
    if (now > next_read) {
      const auto missed = (now - next_read) / timing_.period + 1;
      stats.overruns += static_cast<std::uint64_t>(missed);
      deadline += missed * timing_.period;
    }
    stats_.publish(stats);
  }
}

void AnalogIoWorker::write_pending(DacCommand& written, bool& have_written) noexcept {
  DacCommand wanted = written;
  if (!command_.try_read(wanted) && have_written) return;  // writer busy: next slot
  const bool unchanged =
      have_written && wanted.safe == written.safe && (wanted.safe || wanted.volts == written.volts);
  // Unchanged commands are not re-sent (a Modbus write costs bus time) unless the last failed
  // or the output's communication watchdog needs to hear from us again.
  const nanoseconds now = clock_.now();
  const nanoseconds rewrite_within = dac_.rewrite_within();
  const bool due_again =
      rewrite_within > nanoseconds::zero() && now - last_write_at_ >= rewrite_within;
  if (unchanged && !last_write_failed_ && !due_again) return;
  last_write_at_ = now;
  // force_safe() retries itself: only its final result counts.
  const int result = wanted.safe ? dac_.force_safe() : dac_.write(wanted.volts);
  ++writes_;
  last_write_failed_ = result != 0;
  failed_in_a_row_ = last_write_failed_ ? failed_in_a_row_ + 1 : 0;
  if (last_write_failed_)
    ++(wanted.safe || failed_in_a_row_ > timing_.dac_failures_tolerated ? dac_faults_
                                                                        : dac_tolerated_);
  written = wanted;
  have_written = true;
}

void AnalogIoWorker::command(double volts) noexcept {
  command_.publish(DacCommand{.volts = volts, .safe = false});
}

void AnalogIoWorker::command_safe() noexcept {
  command_.publish(DacCommand{.volts = 0, .safe = true});
}

AnalogIoStats AnalogIoWorker::stats() const noexcept {
  return stats_.read();
}

}  // namespace weedspray::io
