// SPDX-License-Identifier: Apache-2.0
// The flow meter at high pulse rates: the kernel's interrupt-cnt (Counter subsystem) counts the
// rising edges of gpio-sim line flow_fast in its hard interrupt handler, and
// io::hw::CounterPulseInput reads the total from sysfs. Pulses come as fast as sysfs allows
// (two pwrite calls on gpio-sim's open `pull` file per pulse, from one pinned thread), and
// every one must be counted.
//
// gpio-sim raises each interrupt on the writer's CPU during its write. A generator at normal
// priority is therefore preempted by every threaded handler it wakes (SCHED_FIFO 50) and
// slowed to the consumer's pace, which a real meter never is; at SCHED_FIFO above the irq
// threads it keeps its own pace. Both paces run.
//
// For the documentation, the same generator also runs against GpioPulseInput (libgpiod uAPI v1
// edge events, whose threaded handler merges edges that come faster than it runs) on line
// flow_fast_gpiod, and prints how many it saw; that figure is not asserted.
#include <pthread.h>
#include <sched.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "io/linux/counter_pulse_input.hpp"
#include "io/linux/gpio_pulse_input.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "tests/vm/gpio_sim_chip.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;
using vm_test::GpioSimChip;
using vm_test::GpioSimPullWriter;

// guest-init.sh: chip weedspray-count, lines flow_fast (interrupt-cnt's) and flow_fast_gpiod;
// the counter is named after its platform device, "interrupt-cnt".
constexpr unsigned int kCountedOffset = 0;
constexpr unsigned int kGpiodOffset = 1;
constexpr const char* kCounterName = "interrupt-cnt";
constexpr std::uint64_t kPulses = 50000;
constexpr auto kPoll = 2ms;

enum class Pace {
  kNormalPriority,   // waits for each threaded handler it wakes
  kAboveIrqThreads,  // SCHED_FIFO 60: the kernel's irq threads (50) wait for it
};
constexpr int kAboveIrqThreadsPriority = 60;  // and below ws-pulses (70), which polls

const char* to_string(Pace pace) {
  return pace == Pace::kNormalPriority ? "normal" : "fifo60";
}

struct Burst {
  std::uint64_t pulses = 0;
  std::uint64_t failed_writes = 0;
  std::chrono::nanoseconds started{}, finished{};
  double rate_hz() const {
    return static_cast<double>(pulses) / std::chrono::duration<double>(finished - started).count();
  }
};

// `pulses` rising and falling edges, back to back, from a thread pinned to the last CPU (so the
// scheduler never migrates it mid-burst; gpio-sim raises each interrupt on that CPU).
Burst make_pulses(const GpioSimPullWriter& pull, std::uint64_t pulses, Pace pace) {
  Burst burst;
  bool placed = true;
  std::thread generator([&] {
    cpu_set_t cpus;
    CPU_ZERO(&cpus);
    CPU_SET(static_cast<int>(sysconf(_SC_NPROCESSORS_ONLN)) - 1, &cpus);
    placed = sched_setaffinity(0, sizeof(cpus), &cpus) == 0;
    if (pace == Pace::kAboveIrqThreads) {
      const sched_param param{.sched_priority = kAboveIrqThreadsPriority};
      placed = placed && pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0;
    }
    burst.started = monotonic_now();
    for (std::uint64_t i = 0; i < pulses; ++i) {
      burst.failed_writes += pull.set(true) ? 0 : 1;
      burst.failed_writes += pull.set(false) ? 0 : 1;
    }
    burst.finished = monotonic_now();
  });
  generator.join();
  EXPECT_TRUE(placed) << "pinning or SCHED_FIFO refused: the burst's pace is not the intended";
  burst.pulses = pulses;
  return burst;
}

// Waits until the count has not changed for `quiet` (or `limit` passed).
PulseSnapshot wait_until_settled(const PulseInput& input, std::chrono::nanoseconds quiet = 200ms,
                                 std::chrono::nanoseconds limit = 10s) {
  const auto deadline = monotonic_now() + limit;
  PulseSnapshot s = input.snapshot();
  auto changed_at = monotonic_now();
  while (monotonic_now() - changed_at < quiet && monotonic_now() < deadline) {
    std::this_thread::sleep_for(1ms);
    const PulseSnapshot now = input.snapshot();
    if (now.count != s.count) changed_at = monotonic_now();
    s = now;
  }
  return s;
}

std::string counter_dir() {
  return resolve_counter_device_dir(kCounterName, "/sys/bus/counter/devices");
}

std::string read_line(const std::string& path) {
  std::ifstream in(path);
  std::string text;
  std::getline(in, text);
  return text;
}

class CounterPulseInputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    chip_.pull(kCountedOffset, false);
    chip_.pull(kGpiodOffset, false);
  }
  void TearDown() override { SetUp(); }

  GpioSimChip chip_{"weedspray-count"};
};

TEST_F(CounterPulseInputTest, EnablesTheKernelCounterWhichCountsNothingBefore) {
  const std::string enable = counter_dir() + "/count0/enable";
  const std::string count = counter_dir() + "/count0/count";
  std::ofstream(enable) << "0" << std::flush;
  ASSERT_EQ(read_line(enable), "0");
  const std::string before = read_line(count);
  for (int i = 0; i < 10; ++i) {
    chip_.pull(kCountedOffset, true);
    chip_.pull(kCountedOffset, false);
  }
  EXPECT_EQ(read_line(count), before) << "interrupt-cnt counts only once enabled";

  CounterPulseInput flow({.device = kCounterName, .poll_period = kPoll});
  EXPECT_EQ(read_line(enable), "1");
  for (int i = 0; i < 10; ++i) {
    chip_.pull(kCountedOffset, true);
    chip_.pull(kCountedOffset, false);
  }
  EXPECT_EQ(wait_until_settled(flow).count, 10U);
}

TEST_F(CounterPulseInputTest, CountsEveryPulseOfTheFastestSysfsGeneratorAtBothPaces) {
  CounterPulseInput flow({.device = kCounterName, .poll_period = kPoll});
  EXPECT_EQ(flow.count_path(), counter_dir() + "/count0/count");
  EXPECT_EQ(flow.thread_status(), RtStatus::kRealtime) << "root in the guest: SCHED_FIFO";
  std::this_thread::sleep_for(10 * kPoll);
  ASSERT_EQ(flow.snapshot().count, 0U);
  const std::uint64_t kernel_before = std::stoull(read_line(flow.count_path()));

  const GpioSimPullWriter pull(chip_, kCountedOffset);
  std::uint64_t made = 0;
  for (const Pace pace : {Pace::kNormalPriority, Pace::kAboveIrqThreads}) {
    const Burst burst = make_pulses(pull, kPulses, pace);
    made += burst.pulses;
    ASSERT_EQ(burst.failed_writes, 0U);
    const PulseSnapshot s = wait_until_settled(flow);
    std::printf(
        "WEEDSPRAY-VM-FIGURE counter generator=%s pulses=%llu counted=%llu rate_hz=%.0f "
        "seconds=%.3f\n",
        to_string(pace), static_cast<unsigned long long>(burst.pulses),
        static_cast<unsigned long long>(s.count - (made - burst.pulses)), burst.rate_hz(),
        std::chrono::duration<double>(burst.finished - burst.started).count());
    std::fflush(stdout);

    EXPECT_EQ(s.count, made) << to_string(pace) << " generator at " << burst.rate_hz() << " Hz";
    EXPECT_EQ(std::stoull(read_line(flow.count_path())) - kernel_before, made)
        << "the kernel's own total";
    EXPECT_EQ(s.error_count, 0U);
    EXPECT_EQ(s.overflow_count, 0U);
    // A poll time: after the burst's first pulse, and no later than now.
    EXPECT_GT(s.last_edge_time, burst.started);
    EXPECT_LE(s.last_edge_time, monotonic_now());
  }
}

// Documentation, not a requirement: what libgpiod uAPI v1 edge events see of the same bursts.
TEST_F(CounterPulseInputTest, ReportsWhatGpiodEdgeEventsSeeOfTheSameBursts) {
  GpioPulseInput flow({.chip = chip_.label(),
                       .line = {.name = "flow_fast_gpiod"},
                       .counted_edge = PulseEdge::kRising,
                       .consumer = "vm-counter-test"});
  const GpioSimPullWriter pull(chip_, kGpiodOffset);
  PulseSnapshot before{};
  for (const Pace pace : {Pace::kNormalPriority, Pace::kAboveIrqThreads}) {
    const Burst burst = make_pulses(pull, kPulses, pace);
    ASSERT_EQ(burst.failed_writes, 0U);
    const PulseSnapshot s = wait_until_settled(flow);
    const std::uint64_t counted = s.count - before.count;
    const std::uint64_t overflow_reports = s.overflow_count - before.overflow_count;
    before = s;
    std::printf(
        "WEEDSPRAY-VM-FIGURE gpiod_uapi_v1 generator=%s pulses=%llu counted=%llu rate_hz=%.0f "
        "overflow_reports=%llu\n",
        to_string(pace), static_cast<unsigned long long>(burst.pulses),
        static_cast<unsigned long long>(counted), burst.rate_hz(),
        static_cast<unsigned long long>(overflow_reports));
    std::fflush(stdout);
    EXPECT_GT(counted, 0U);
    EXPECT_LE(counted, kPulses) << "never more edges than were made";
  }
}

}  // namespace
}  // namespace weedspray::io::hw
