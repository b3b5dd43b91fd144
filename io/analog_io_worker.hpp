// SPDX-License-Identifier: Apache-2.0
// The pressure converters' own thread. Reading the pressure ADC and writing the return-valve
// DAC block: an ADS1115 behind IIO converts for 1-8 ms per read over I2C, a Modbus analog
// module takes a 2-20 ms transaction and, when it stops answering, a whole response timeout.
// The pressure loop must not wait on any of that, so this worker does the I/O and the loop only
// exchanges values with it, wait-free:
//
//   deadline k of the pressure loop:    ... |<- lead ->|D_k|<- lag ->| ...
//   this worker:                            read ADC,      write the newest DAC command
//                                           publish        the loop left
//
// The read starts `lead` before each loop deadline so a fresh sample is waiting when the loop
// wakes; `lead` follows the converter (1.5 x a decaying maximum of recent read times + margin,
// clamped to half a period), so a fast IIO chip adds well under a millisecond of dead time and a
// slow Modbus module gets the time it needs. The DAC write follows the loop by `lag`.
// One thread for both converters: modules sharing one RS-485 bus are never addressed at once.
// A read that hangs leaves the published sample ageing; the loop checks the age
// (sample_is_fresh) and goes safe instead of waiting.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <stop_token>

#include "io/analog.hpp"
#include "io/clock.hpp"
#include "io/latest_value.hpp"

namespace weedspray::io {

struct AnalogIoTiming {
  std::chrono::nanoseconds period{std::chrono::milliseconds(10)};  // the pressure loop's
  std::chrono::nanoseconds min_lead{std::chrono::microseconds(300)};
  std::chrono::nanoseconds lag{std::chrono::milliseconds(1)};  // after the loop's deadline
  // Failed DAC writes in a row that count as superseded, not as an output fault: a Modbus
  // module that misses one answer (noise on the RS-485 pair, a busy module) gets the newer
  // command one period later anyway, and the return valve held its last value meanwhile. The
  // next failure in the streak is a fault (dac_faults). A failed safe write never is tolerated.
  std::uint32_t dac_failures_tolerated = 0;
};

struct AnalogIoStats {
  std::uint64_t reads = 0;
  std::uint64_t writes = 0;
  std::uint64_t dac_errors = 0;  // failed DAC writes (the device's count)
  // Of those, the ones that are faults: beyond dac_failures_tolerated in a row, or safe writes.
  std::uint64_t dac_faults = 0;
  // Failed writes tolerated as superseded (counted here, not derived from dac_errors: that
  // device count also holds force_safe()'s own retries).
  std::uint64_t dac_tolerated = 0;
  std::uint64_t overruns = 0;  // read slots missed because the previous I/O ran long
  std::chrono::nanoseconds lead{0};
  std::chrono::nanoseconds max_read_time{0};
};

class AnalogIoWorker {
 public:
  // `adc` and `dac` are used only from run()'s thread while it runs.
  AnalogIoWorker(AnalogInput& adc, AnalogOutput& dac, Clock& clock, AnalogIoTiming timing) noexcept;

  // The thread body (io::ThreadRole::kAnalogIo). The pressure loop's deadlines are
  // first_deadline + k * period. Returns when `stop` is requested; it does not touch the
  // outputs on the way out (the owner forces them safe after joining).
  void run(std::stop_token stop, std::chrono::nanoseconds first_deadline) noexcept;

  // --- the pressure loop's side: wait-free, no I/O ---
  // Copies the newest sample into `out` (ok = false until the first read). Returns false,
  // leaving `out` as it was, in the rare case the slot was being written all along.
  bool try_latest_sample(AnalogSample& out) const noexcept { return sample_.try_read(out); }
  // True when `sample` was taken within `max_age` of `now`.
  static bool sample_is_fresh(const AnalogSample& sample, std::chrono::nanoseconds now,
                              std::chrono::nanoseconds max_age) noexcept {
    return sample.ok && now - sample.time <= max_age;
  }
  // The DAC voltage to write at the next write slot.
  void command(double volts) noexcept;
  // The DAC's safe voltage (return valve open) at the next write slot.
  void command_safe() noexcept;

  // Any thread.
  AnalogIoStats stats() const noexcept;

 private:
  struct DacCommand {
    double volts = 0;
    bool safe = true;
  };

  void write_pending(DacCommand& written, bool& have_written) noexcept;
  std::chrono::nanoseconds lead_for(std::chrono::nanoseconds read_time_estimate) const noexcept;

  AnalogInput& adc_;
  AnalogOutput& dac_;
  Clock& clock_;
  AnalogIoTiming timing_;
  LatestValue<AnalogSample> sample_;
  LatestValue<DacCommand> command_{DacCommand{}};
  LatestValue<AnalogIoStats> stats_;
  std::uint64_t writes_ = 0;                  // run()'s thread only
  bool last_write_failed_ = false;            // run()'s thread only
  std::uint32_t failed_in_a_row_ = 0;         // run()'s thread only
  std::uint64_t dac_faults_ = 0;              // run()'s thread only
  std::uint64_t dac_tolerated_ = 0;           // run()'s thread only
  std::chrono::nanoseconds last_write_at_{};  // run()'s thread only
};

}  // namespace weedspray::io
