// SPDX-License-Identifier: Apache-2.0
// io::AnalogIoWorker: the schedule of converter reads/writes around the pressure loop's
// deadlines, the adaptive lead, and that a hung converter never blocks the loop's side.
#include "io/analog_io_worker.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "io/sim/manual_clock.hpp"
#include "io/sim/paced_clock.hpp"

namespace weedspray::io {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

// An ADC whose conversion takes `conversion` of (manual) time and stops the worker after
// `stop_after` reads.
class TimedAdc final : public AnalogInput {
 public:
  TimedAdc(sim::ManualClock& clock, nanoseconds conversion)
      : clock_(clock), conversion_(conversion) {}
  AnalogSample read() noexcept override {
    started.push_back(clock_.now());
    clock_.advance(conversion_);
    if (static_cast<int>(started.size()) >= stop_after) stop.request_stop();
    return {.volts = 1.0 + static_cast<double>(started.size()),
            .time = clock_.now(),
            .error_count = 0,
            .ok = true};
  }
  void set_conversion(nanoseconds c) { conversion_ = c; }
  std::vector<nanoseconds> started;
  int stop_after = 20;
  std::stop_source stop;

 private:
  sim::ManualClock& clock_;
  nanoseconds conversion_;
};

class RecordingDac final : public AnalogOutput {
 public:
  explicit RecordingDac(const Clock& clock) : clock_(clock) {}
  int write(double volts) noexcept override {
    writes.push_back({clock_.now(), volts});
    const bool fail = fail_writes || (!fail_pattern.empty() &&
                                      fail_pattern[(writes.size() - 1) % fail_pattern.size()]);
    if (fail) {
      ++errors_;
      return -5;
    }
    return 0;
  }
  int force_safe() noexcept override {
    writes.push_back({clock_.now(), kSafe});
    if (fail_safe) {
      ++errors_;
      return -5;
    }
    return 0;
  }
  double full_scale_volts() const noexcept override { return 3.3; }
  std::uint64_t error_count() const noexcept override { return errors_; }
  nanoseconds rewrite_within() const noexcept override { return rewrite; }

  static constexpr double kSafe = -1.0;
  nanoseconds rewrite{};  // a module watchdog's need to hear from the daemon
  struct Write {
    nanoseconds time;
    double volts;
  };
  std::vector<Write> writes;
  bool fail_writes = false;
  std::vector<bool> fail_pattern;  // write k fails if fail_pattern[k % size]
  bool fail_safe = false;

 private:
  const Clock& clock_;
  std::uint64_t errors_ = 0;
};

constexpr nanoseconds kPeriod = 10ms;
constexpr nanoseconds kFirstDeadline = 1s;

AnalogIoTiming timing() {
  return {.period = kPeriod, .min_lead = 300us, .lag = 1ms};
}

TEST(AnalogIoWorker, ReadsJustBeforeEachDeadlineAndPublishesTheSample) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 0ns);
  RecordingDac dac(clock);
  AnalogIoWorker worker(adc, dac, clock, timing());
  AnalogSample sample;
  ASSERT_TRUE(worker.try_latest_sample(sample));
  EXPECT_FALSE(sample.ok) << "no sample before the first read";

  worker.run(adc.stop.get_token(), kFirstDeadline);
  ASSERT_EQ(adc.started.size(), 20U);
  for (std::size_t k = 0; k < adc.started.size(); ++k) {
    // With an instant converter the lead is its minimum.
    EXPECT_EQ(adc.started[k], kFirstDeadline + static_cast<long>(k) * kPeriod - 300us) << k;
  }
  ASSERT_TRUE(worker.try_latest_sample(sample));
  EXPECT_TRUE(sample.ok);
  EXPECT_DOUBLE_EQ(sample.volts, 21.0);  // the 20th read
  EXPECT_EQ(worker.stats().reads, 20U);
  EXPECT_EQ(worker.stats().overruns, 0U);
}

TEST(AnalogIoWorker, LeadGrowsWithASlowConverterSoTheSampleIsReadyAtTheDeadline) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 2ms);  // e.g. a Modbus module at 115200 baud
  RecordingDac dac(clock);
  AnalogIoWorker worker(adc, dac, clock, timing());
  worker.run(adc.stop.get_token(), kFirstDeadline);
  ASSERT_EQ(adc.started.size(), 20U);
  // After the first read has been timed, every read ends before its deadline.
  for (std::size_t k = 1; k < adc.started.size(); ++k) {
    const nanoseconds deadline = kFirstDeadline + static_cast<long>(k) * kPeriod;
    EXPECT_LE(adc.started[k] + 2ms, deadline) << k;
    EXPECT_GE(adc.started[k], deadline - 5ms) << "lead is at most half a period; read " << k;
  }
  EXPECT_EQ(worker.stats().lead, 2ms * 3 / 2 + 300us);
  EXPECT_EQ(worker.stats().max_read_time, 2ms);
}

TEST(AnalogIoWorker, LeadIsCappedAtHalfAPeriodAndLongReadsCountOverruns) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 25ms);  // a converter slower than the loop itself
  adc.stop_after = 5;
  RecordingDac dac(clock);
  AnalogIoWorker worker(adc, dac, clock, timing());
  worker.run(adc.stop.get_token(), kFirstDeadline);
  const AnalogIoStats stats = worker.stats();
  EXPECT_EQ(stats.lead, kPeriod / 2);
  // Each 25 ms read eats the next read slots: at least two of every three are missed.
  EXPECT_GE(stats.overruns, 2U * (stats.reads - 1));
}

TEST(AnalogIoWorker, WritesTheNewestCommandAfterTheDeadlineAndOnlyWhenItChanges) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 0ns);
  adc.stop_after = 6;
  RecordingDac dac(clock);
  AnalogIoWorker worker(adc, dac, clock, timing());
  worker.command(1.0);
  worker.command(1.5);  // only the newest counts
  worker.run(adc.stop.get_token(), kFirstDeadline);
  ASSERT_EQ(dac.writes.size(), 1U) << "an unchanged command is not re-sent";
  EXPECT_EQ(dac.writes[0].time, kFirstDeadline + 1ms);
  EXPECT_DOUBLE_EQ(dac.writes[0].volts, 1.5);

  worker.command_safe();
  adc.stop = {};
  adc.stop_after = 8;
  worker.run(adc.stop.get_token(), clock.now() + kPeriod);
  ASSERT_EQ(dac.writes.size(), 2U);
  EXPECT_EQ(dac.writes[1].volts, RecordingDac::kSafe);
}

// A Modbus module with a communication watchdog puts its output safe when no write arrives
// within its timeout: an unchanged command is written again once rewrite_within has passed.
TEST(AnalogIoWorker, AnUnchangedCommandIsRewrittenBeforeTheOutputsWatchdogExpires) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 0ns);
  adc.stop_after = 13;
  RecordingDac dac(clock);
  dac.rewrite = 30ms;
  AnalogIoWorker worker(adc, dac, clock, timing());
  worker.command(1.5);
  worker.run(adc.stop.get_token(), kFirstDeadline);
  ASSERT_EQ(dac.writes.size(), 5U) << "slots 0, 3, 6, 9 and 12 of 13";
  for (std::size_t i = 0; i < dac.writes.size(); ++i) {
    EXPECT_DOUBLE_EQ(dac.writes[i].volts, 1.5);
    EXPECT_EQ(dac.writes[i].time, kFirstDeadline + 1ms + static_cast<int>(i) * 3 * kPeriod);
  }
}

TEST(AnalogIoWorker, AFailedWriteIsRetriedAtTheNextSlot) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 0ns);
  adc.stop_after = 4;
  RecordingDac dac(clock);
  dac.fail_writes = true;
  AnalogIoWorker worker(adc, dac, clock, timing());
  worker.command(2.0);
  worker.run(adc.stop.get_token(), kFirstDeadline);
  EXPECT_EQ(dac.writes.size(), 4U) << "every slot retries the failed command";
  EXPECT_EQ(worker.stats().dac_errors, 4U);
  EXPECT_EQ(worker.stats().writes, 4U);
}

// A Modbus module that misses an answer now and then is no fault: the next period's write
// supersedes it. A streak longer than tolerated is, and so is any failed safe write.
TEST(AnalogIoWorker, OnlyFailuresBeyondTheToleratedStreakAreFaults) {
  sim::ManualClock clock;
  TimedAdc adc(clock, 0ns);
  adc.stop_after = 12;
  RecordingDac dac(clock);
  AnalogIoTiming t = timing();
  t.dac_failures_tolerated = 2;
  {
    // Two failures, then the retry gets through: tolerated.
    dac.fail_pattern = {true, true, false};
    AnalogIoWorker worker(adc, dac, clock, t);
    worker.command(1.0);
    worker.run(adc.stop.get_token(), kFirstDeadline);
    EXPECT_EQ(dac.writes.size(), 3U);
    EXPECT_EQ(worker.stats().dac_errors, 2U);
    EXPECT_EQ(worker.stats().dac_faults, 0U);
    EXPECT_EQ(worker.stats().dac_tolerated, 2U);
  }
  {
    // Every write fails: slots 1-2 tolerated, 3 and later faults.
    dac.fail_pattern.clear();
    dac.fail_writes = true;
    adc.stop = {};
    adc.started.clear();
    adc.stop_after = 5;
    AnalogIoWorker worker(adc, dac, clock, t);
    worker.command(2.0);
    worker.run(adc.stop.get_token(), clock.now() + kPeriod);
    EXPECT_EQ(worker.stats().dac_faults, 3U);
    EXPECT_EQ(worker.stats().dac_tolerated, 2U);
  }
  {
    // A safe write that fails is a fault at once.
    dac.fail_writes = false;
    dac.fail_safe = true;
    adc.stop = {};
    adc.started.clear();
    adc.stop_after = 1;
    AnalogIoWorker worker(adc, dac, clock, t);
    worker.command_safe();
    worker.run(adc.stop.get_token(), clock.now() + kPeriod);
    EXPECT_EQ(worker.stats().dac_faults, 1U);
  }
}

TEST(AnalogIoWorker, FreshnessIsJudgedOnTheSampleTime) {
  const AnalogSample sample{.volts = 1, .time = 100ms, .error_count = 0, .ok = true};
  EXPECT_TRUE(AnalogIoWorker::sample_is_fresh(sample, 130ms, 30ms));
  EXPECT_FALSE(AnalogIoWorker::sample_is_fresh(sample, 131ms, 30ms));
  AnalogSample failed = sample;
  failed.ok = false;
  EXPECT_FALSE(AnalogIoWorker::sample_is_fresh(failed, 100ms, 30ms));
}

// A converter that hangs inside read() until released (an I2C bus stuck low, a Modbus module
// gone silent with a long timeout).
class HangingAdc final : public AnalogInput {
 public:
  AnalogSample read() noexcept override {
    std::unique_lock lock(mutex_);
    ++reads_;
    entered_.notify_all();
    released_cv_.wait(lock, [&] { return released_; });
    return {.volts = 2.0, .time = {}, .error_count = 0, .ok = true};
  }
  void wait_until_inside() {
    std::unique_lock lock(mutex_);
    entered_.wait(lock, [&] { return reads_ > 0; });
  }
  void release() {
    std::lock_guard lock(mutex_);
    released_ = true;
    released_cv_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable entered_;
  std::condition_variable released_cv_;
  int reads_ = 0;
  bool released_ = false;
};

TEST(AnalogIoWorker, AHungConverterNeverBlocksTheLoopSide) {
  sim::PacedClock clock;
  HangingAdc adc;
  RecordingDac dac(clock);
  AnalogIoWorker worker(adc, dac, clock, timing());
  std::jthread thread([&](std::stop_token stop) { worker.run(stop, clock.now() + kPeriod); });
  adc.wait_until_inside();
  // The worker is stuck in read(): the loop's side still answers at once (a deadlock here would
  // hang the test, not pass it).
  for (int i = 0; i < 1000; ++i) {
    AnalogSample sample;
    EXPECT_TRUE(worker.try_latest_sample(sample));
    EXPECT_FALSE(sample.ok);
    worker.command(0.1 * i);
    worker.command_safe();
  }
  EXPECT_EQ(worker.stats().reads, 0U);
  adc.release();
  thread.request_stop();
  thread.join();
  AnalogSample sample;
  ASSERT_TRUE(worker.try_latest_sample(sample));
  EXPECT_TRUE(sample.ok) << "the released read is published";
  ASSERT_FALSE(dac.writes.empty());
  EXPECT_EQ(dac.writes.back().volts, RecordingDac::kSafe) << "the newest command is the one sent";
}

}  // namespace
}  // namespace weedspray::io
