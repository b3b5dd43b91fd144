// SPDX-License-Identifier: Apache-2.0
#include "io/valve_pwm_driver.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cerrno>
#include <functional>
#include <stop_token>

#include "control/pwm_schedule.hpp"
#include "io/sim/manual_clock.hpp"
#include "io/sim/memory_output_bank.hpp"
#include "io/sim/simulated_machine.hpp"

namespace weedspray::io {
namespace {

using namespace std::chrono_literals;
using std::chrono::nanoseconds;

// Simulated time that advances when slept on, with a hook run at every sleep (the test's
// "other threads": command refreshes) and a stop at a given time, so run() executes
// deterministically on the test thread.
class ScriptedClock final : public Clock {
 public:
  nanoseconds now() const noexcept override { return inner.now(); }
  void sleep_until(nanoseconds t) noexcept override {
    inner.sleep_until(t);
    if (on_sleep) on_sleep(inner.now());
    if (inner.now() >= stop_at) stop.request_stop();
  }
  sim::ManualClock inner;
  std::function<void(nanoseconds)> on_sleep;
  nanoseconds stop_at{1s};
  std::stop_source stop;
};

struct Rig {
  ScriptedClock clock;
  sim::MemoryOutputBank bank{4, 0, clock, 100000};
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  ValvePwmDriver<control::PwmSchedule> driver;

  explicit Rig(ValvePwmDriverConfig config) : driver(clock, bank, schedule, config) {}

  static ValveCommand command(nanoseconds at) {
    ValveCommand c;
    c.valve_count = 4;
    c.duty_pct[0] = 25;
    c.duty_pct[1] = 50;
    c.duty_pct[2] = 75;
    c.duty_pct[3] = 40;
    c.issued_at = at;
    return c;
  }
};

// Time each valve spent open in [from, to), from the bank's write history.
std::array<double, 4> open_fraction(const std::vector<sim::OutputWrite>& writes, nanoseconds from,
                                    nanoseconds to) {
  std::array<double, 4> open_ns{};
  std::uint32_t mask = 0;
  nanoseconds t = from;
  for (const auto& w : writes) {
    if (w.time >= to) break;
    if (w.time > t) {
      for (int v = 0; v < 4; ++v)
        if (mask & (1U << v)) open_ns[v] += static_cast<double>((w.time - t).count());
      t = w.time;
    }
    mask = w.mask;
  }
  for (int v = 0; v < 4; ++v)
    if (mask & (1U << v)) open_ns[v] += static_cast<double>((to - t).count());
  for (auto& o : open_ns) o /= static_cast<double>((to - from).count());
  return open_ns;
}

TEST(ValvePwmDriver, ExecutesTheScheduleEdgeForEdgeOnTime) {
  ValvePwmDriverConfig config;
  config.command_expiry = 10s;
  Rig machine(config);
  machine.driver.command(Rig::command(0ns));
  machine.clock.stop_at = 2s;
  machine.driver.run(machine.clock.stop.get_token());

  const ValvePwmStats stats = machine.driver.stats();
  EXPECT_EQ(stats.deadman_expiries, 0U);
  EXPECT_EQ(stats.late_edges, 0U);
  EXPECT_EQ(stats.skipped_edges, 0U);
  EXPECT_EQ(stats.schedule_start, 0ns);

  // The same schedule, computed independently, gives every write's time and mask.
  control::PwmSchedule reference(machine.pwm_config);
  const auto cmd = Rig::command(0ns);
  reference.set_duties(std::span<const double>(cmd.duty_pct.data(), 4));
  reference.start(0ns);
  const auto writes = machine.bank.history();
  ASSERT_GT(writes.size(), 40U);
  EXPECT_EQ(writes.size(), stats.edges_written);
  for (const auto& w : writes) {
    const control::PwmEdge edge = reference.next_edge();
    EXPECT_EQ(w.time, edge.time);
    EXPECT_EQ(w.mask, edge.valve_mask);
  }
  // Duties over whole periods after the first (latching) period.
  const auto duty = open_fraction(writes, 400ms, 1800ms);
  EXPECT_NEAR(duty[0], 0.25, 1e-6);
  EXPECT_NEAR(duty[1], 0.50, 1e-6);
  EXPECT_NEAR(duty[2], 0.75, 1e-6);
  EXPECT_NEAR(duty[3], 0.40, 1e-6);
  EXPECT_EQ(machine.bank.mask(), 0U) << "valves closed after run() returns";
  EXPECT_GE(machine.bank.force_safe_count(), 2U) << "force_safe at start and at stop";
}

TEST(ValvePwmDriver, DeadManClosesAllValvesWhenCommandsStop) {
  ValvePwmDriverConfig config;
  config.command_expiry = 300ms;
  Rig machine(config);
  machine.driver.command(Rig::command(0ns));
  nanoseconds expired_seen{-1};
  std::uint64_t force_safe_before = 0;
  machine.clock.on_sleep = [&](nanoseconds now) {
    if (expired_seen < 0ns && machine.driver.stats().expired && now > 0ns) {
      expired_seen = now;
      force_safe_before = machine.bank.force_safe_count();
    }
  };
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());

  const ValvePwmStats stats = machine.driver.stats();
  EXPECT_EQ(stats.deadman_expiries, 1U);
  EXPECT_GE(expired_seen, 300ms);
  EXPECT_LE(expired_seen, 300ms + config.max_sleep);
  EXPECT_GE(force_safe_before, 2U) << "force_safe at start and at expiry";
  for (const auto& w : machine.bank.history())
    EXPECT_LT(w.time, 300ms) << "no valve write after the command expired";
  EXPECT_EQ(machine.bank.mask(), 0U);
}

TEST(ValvePwmDriver, RefreshedCommandsKeepValvesRunning) {
  ValvePwmDriverConfig config;
  config.command_expiry = 300ms;
  Rig machine(config);
  machine.driver.command(Rig::command(0ns));
  nanoseconds last_refresh = 0ns;
  machine.clock.on_sleep = [&](nanoseconds now) {
    if (now - last_refresh >= 100ms) {
      last_refresh = now;
      machine.driver.command(Rig::command(now));
    }
  };
  machine.clock.stop_at = 3s;
  machine.driver.run(machine.clock.stop.get_token());
  const ValvePwmStats stats = machine.driver.stats();
  EXPECT_EQ(stats.deadman_expiries, 0U);
  EXPECT_GT(stats.commands_applied, 25U);
  const auto duty = open_fraction(machine.bank.history(), 400ms, 2800ms);
  EXPECT_NEAR(duty[1], 0.50, 1e-6);
}

TEST(ValvePwmDriver, ResumesAfterExpiryWhenCommandsReturn) {
  ValvePwmDriverConfig config;
  config.command_expiry = 200ms;
  Rig machine(config);
  machine.driver.command(Rig::command(0ns));
  bool resumed = false;
  machine.clock.on_sleep = [&](nanoseconds now) {
    if (!resumed && now >= 1s) {
      resumed = true;
      ValveCommand c = Rig::command(now);
      c.issued_at = now;
      machine.driver.command(c);
    }
  };
  machine.clock.stop_at = 1150ms;
  machine.driver.run(machine.clock.stop.get_token());
  const ValvePwmStats stats = machine.driver.stats();
  EXPECT_EQ(stats.deadman_expiries, 1U);
  EXPECT_GE(stats.schedule_start, 1s) << "phases restarted when commands returned";
  bool wrote_after_resume = false;
  for (const auto& w : machine.bank.history())
    if (w.time >= 1s && w.mask != 0) wrote_after_resume = true;
  EXPECT_TRUE(wrote_after_resume);
  EXPECT_EQ(stats.late_edges, 0U);
}

// With the immediate schedule, a spray start/stop is written when the command arrives, not at
// the valve's next period start (nor one fetched edge later).
TEST(ValvePwmDriver, AppliesAnImmediateStartAndStopWhenTheCommandArrives) {
  ScriptedClock clock;
  sim::MemoryOutputBank bank{4, 0, clock, 100000};
  control::PwmConfig pwm;
  pwm.immediate_start_stop = true;
  control::PwmSchedule schedule(pwm);
  ValvePwmDriverConfig config;
  config.command_expiry = 10s;
  ValvePwmDriver<control::PwmSchedule> driver(clock, bank, schedule, config);
  ValveCommand closed;
  closed.valve_count = 4;
  driver.command(closed);
  ValveCommand spray_valve_2 = closed;
  spray_valve_2.duty_pct[2] = 60;  // valve 2's slot: 150 ms + k*200 ms
  nanoseconds started_at{-1};
  nanoseconds stopped_at{-1};
  clock.on_sleep = [&](nanoseconds now) {
    if (started_at < 0ns && now >= 363ms) {
      started_at = now;
      spray_valve_2.issued_at = now;
      driver.command(spray_valve_2);
    } else if (stopped_at < 0ns && now >= 407ms) {
      stopped_at = now;
      closed.issued_at = now;
      driver.command(closed);
    }
  };
  clock.stop_at = 1s;
  driver.run(clock.stop.get_token());

  ASSERT_GE(started_at, 363ms);
  ASSERT_LT(started_at, 363ms + config.max_sleep);
  std::vector<sim::OutputWrite> valve_2_changes;
  std::uint32_t previous = 0;
  for (const auto& w : bank.history()) {
    if ((w.mask ^ previous) & 4u) valve_2_changes.push_back(w);
    previous = w.mask;
  }
  ASSERT_EQ(valve_2_changes.size(), 2U) << "opened once, closed once";
  EXPECT_EQ(valve_2_changes[0].time, started_at) << "not at the 550 ms period start";
  EXPECT_EQ(valve_2_changes[0].mask & 4u, 4u);
  EXPECT_EQ(valve_2_changes[1].time, stopped_at) << "not at the end of the 120 ms pulse";
  EXPECT_EQ(valve_2_changes[1].mask & 4u, 0u);
  EXPECT_EQ(driver.stats().late_edges, 0U);
}

TEST(ValvePwmDriver, NoCommandMeansNoValveEverOpens) {
  Rig machine(ValvePwmDriverConfig{});
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());
  EXPECT_TRUE(machine.bank.history().empty());
  EXPECT_EQ(machine.bank.mask(), 0U);
  EXPECT_EQ(machine.driver.stats().edges_written, 0U);
}

// The driver on the simulated machine: the plant's valves follow the duties (more duty, more
// liquid) and every valve ends closed.
TEST(ValvePwmDriver, DrivesThePlantValvesAndLeavesThemClosed) {
  ScriptedClock clock;
  sim::SimulatedMachine machine(sim::SimulatedMachineConfig{}, clock);
  sim::SimulatedValveBank valves(machine);
  sim::SimulatedPumpRelay pump(machine);
  sim::SimulatedReturnValveDac dac(machine, ValveDriveConfig{});
  pump.write(1);
  dac.write(0.3);
  control::PwmConfig pwm;
  control::PwmSchedule schedule(pwm);
  ValvePwmDriverConfig config;
  config.command_expiry = 10s;
  ValvePwmDriver<control::PwmSchedule> driver(clock, valves, schedule, config);
  ValveCommand cmd;
  cmd.valve_count = 4;
  cmd.duty_pct = {20, 40, 60, 80};
  cmd.issued_at = 0ns;
  driver.command(cmd);
  std::uint32_t max_mask_seen = 0;
  clock.on_sleep = [&](nanoseconds) { max_mask_seen |= valves.mask(); };
  clock.stop_at = 5s;
  driver.run(clock.stop.get_token());

  EXPECT_EQ(max_mask_seen, 0xFU) << "every valve opened at some point";
  EXPECT_EQ(valves.mask(), 0U) << "every valve ended closed";
  std::array<double, 4> delivered{};
  machine.with_plant([&](auto& plant) {
    for (int i = 0; i < 4; ++i)
      delivered[static_cast<std::size_t>(i)] = plant.nozzle_delivered_l(i);
  });
  for (std::size_t i = 1; i < 4; ++i)
    EXPECT_GT(delivered[i], delivered[i - 1] * 1.2) << "nozzle " << i << " has more duty";
  EXPECT_GT(delivered[0], 0.0);
  double plant_time_s = 0.0;
  machine.with_plant([&](auto& plant) { plant_time_s = plant.time_s(); });
  EXPECT_NEAR(plant_time_s, 5.0, 0.05) << "the plant followed the clock";
  RecordProperty("delivered_l", std::to_string(delivered[0]) + " " + std::to_string(delivered[1]) +
                                    " " + std::to_string(delivered[2]) + " " +
                                    std::to_string(delivered[3]));
}

TEST(ValvePwmDriver, HeartbeatIsASquareWaveWhileRunningAndLowAfter) {
  ValvePwmDriverConfig config;
  config.command_expiry = 10s;
  ScriptedClock clock;
  sim::MemoryOutputBank heartbeat{1, 0, clock, 1000};
  config.heartbeat = &heartbeat;
  config.heartbeat_half_period = 10ms;  // 50 Hz
  sim::MemoryOutputBank bank{4, 0, clock, 1000};
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  ValvePwmDriver<control::PwmSchedule> driver(clock, bank, schedule, config);
  driver.command(Rig::command(0ns));
  clock.stop_at = 1s;
  driver.run(clock.stop.get_token());

  const auto writes = heartbeat.history();
  ASSERT_GE(writes.size(), 99U);
  for (std::size_t i = 1; i < writes.size(); ++i) {
    EXPECT_NE(writes[i].mask, writes[i - 1].mask) << "every write toggles";
    EXPECT_EQ(writes[i].time - writes[i - 1].time, 10ms) << "edge " << i;
  }
  EXPECT_EQ(driver.stats().heartbeat_toggles, writes.size());
  EXPECT_EQ(heartbeat.mask(), 0U) << "low once the loop has stopped: the relay drops";
}

// A driver with a 50 Hz heartbeat and a fresh command, for the heartbeat's stop tests.
struct HeartbeatRig {
  ScriptedClock clock;
  sim::MemoryOutputBank heartbeat{1, 0, clock, 1000};
  sim::MemoryOutputBank bank{4, 0, clock, 1000};
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  ValvePwmDriver<control::PwmSchedule> driver{clock, bank, schedule, config()};

  HeartbeatRig() { driver.command(Rig::command(0ns)); }
  ValvePwmDriverConfig config() {
    ValvePwmDriverConfig c;
    c.command_expiry = 10s;
    c.heartbeat = &heartbeat;
    c.heartbeat_half_period = 10ms;
    return c;
  }
};

// The heartbeat stops (low, no more toggles) when told to - a latched Fault - and beats again
// when resumed; the relay it holds then drops within its hold-up time.
TEST(ValvePwmDriver, HeartbeatStopsWhenToldAndBeatsAgainWhenResumed) {
  HeartbeatRig machine;
  std::uint64_t toggles_at_stop = 0;
  bool low_while_stopped = true;
  machine.clock.on_sleep = [&](nanoseconds now) {
    if (now >= 300ms && now < 310ms) {
      machine.driver.stop_heartbeat();
      toggles_at_stop = machine.heartbeat.write_count();
    }
    if (now >= 350ms && now < 700ms && machine.heartbeat.mask() != 0) low_while_stopped = false;
    if (now >= 700ms) machine.driver.resume_heartbeat();
  };
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());

  EXPECT_TRUE(low_while_stopped);
  std::size_t toggles_while_stopped = 0;
  std::size_t toggles_after = 0;
  for (const auto& write : machine.heartbeat.history()) {
    if (write.time > 330ms && write.time < 700ms) ++toggles_while_stopped;
    if (write.time > 720ms) ++toggles_after;
  }
  EXPECT_GT(toggles_at_stop, 25U) << "it beat before";
  EXPECT_EQ(toggles_while_stopped, 0U);
  EXPECT_GT(toggles_after, 20U) << "it beats again once resumed";
  EXPECT_EQ(machine.heartbeat.mask(), 0U);
}

// A refused valve write may leave a valve open: the heartbeat stops at once, from the valve
// thread itself, and stays stopped (until resumed) even when the writes work again.
TEST(ValvePwmDriver, AFailedValveWriteStopsTheHeartbeat) {
  HeartbeatRig machine;
  nanoseconds failed_at{0};
  machine.clock.on_sleep = [&](nanoseconds now) {
    if (now >= 400ms && failed_at == 0ns) {
      machine.bank.fail_writes(EIO);
      failed_at = now;
    }
    if (now >= 500ms) machine.bank.fail_writes(0);
  };
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());

  ASSERT_GT(machine.driver.stats().write_errors, 0U) << "the failure was not reached";
  nanoseconds last_toggle{0};
  for (const auto& write : machine.heartbeat.history()) {
    if (write.mask != 0) last_toggle = write.time;
  }
  EXPECT_GT(last_toggle, 300ms) << "it beat before";
  // Stopped by the first refused edge: a 5 Hz schedule of four valves has one every 50 ms.
  EXPECT_LT(last_toggle, failed_at + 100ms);
  EXPECT_TRUE(machine.driver.stats().heartbeat_stopped);
  EXPECT_EQ(machine.heartbeat.mask(), 0U);
}

// A driver with a 50 Hz heartbeat, a hold flag (the E-stop's latch) and commands refreshed
// every 50 ms by refresh().
struct HoldRig {
  ScriptedClock clock;
  sim::MemoryOutputBank heartbeat{1, 0, clock, 1000};
  sim::MemoryOutputBank bank{4, 0, clock, 1000};
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  std::atomic<bool> hold{false};
  std::atomic<bool> close{false};
  ValvePwmDriver<control::PwmSchedule> driver{clock, bank, schedule, config()};
  nanoseconds last_refresh{-1s};

  ValvePwmDriverConfig config() {
    ValvePwmDriverConfig c;
    c.command_expiry = 10s;
    c.heartbeat = &heartbeat;
    c.heartbeat_half_period = 10ms;
    c.hold_safe = &hold;
    c.hold_closed = &close;
    c.max_sleep = 2ms;
    return c;
  }
  void refresh(nanoseconds now) {
    if (now - last_refresh >= 50ms) {
      last_refresh = now;
      driver.command(Rig::command(now));
    }
  }
};

// While held, no valve opens and the heartbeat stays low, commands or not; released, the
// valves follow their commands again and the heartbeat beats.
TEST(ValvePwmDriver, AHoldClosesTheValvesAndStopsTheHeartbeatUntilReleased) {
  HoldRig machine;
  bool valve_open_while_held = false;
  bool heartbeat_high_while_held = false;
  machine.clock.on_sleep = [&](nanoseconds now) {
    machine.refresh(now);
    if (now >= 300ms && now < 700ms) machine.hold = true;
    if (now >= 700ms) machine.hold = false;
    // One wake (max_sleep) after the hold is set, everything must be safe.
    if (now >= 303ms && now < 700ms) {
      valve_open_while_held |= machine.bank.mask() != 0;
      heartbeat_high_while_held |= machine.heartbeat.mask() != 0;
    }
  };
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());

  EXPECT_FALSE(valve_open_while_held);
  EXPECT_FALSE(heartbeat_high_while_held);
  EXPECT_EQ(machine.driver.stats().holds, 1U);
  EXPECT_EQ(machine.driver.stats().deadman_expiries, 0U) << "a hold is not a dead-man expiry";
  std::size_t opened_before = 0, opened_after = 0, beats_after = 0;
  for (const auto& w : machine.bank.history()) {
    if (w.mask != 0 && w.time < 300ms) ++opened_before;
    if (w.mask != 0 && w.time > 700ms) ++opened_after;
  }
  for (const auto& w : machine.heartbeat.history())
    if (w.time > 705ms) ++beats_after;
  EXPECT_GT(opened_before, 3U) << "the valves were running before the hold";
  EXPECT_GT(opened_after, 3U) << "and run again once it is released";
  EXPECT_GT(beats_after, 20U);
}

// The pressure loop's hold (a sensor fault): no valve opens while it holds, the heartbeat beats
// on, and the valves follow their commands again once it is released.
TEST(ValvePwmDriver, AClosingHoldKeepsTheValvesClosedAndTheHeartbeatBeating) {
  HoldRig machine;
  bool valve_open_while_held = false;
  machine.clock.on_sleep = [&](nanoseconds now) {
    machine.refresh(now);
    machine.close = now >= 300ms && now < 700ms;
    if (now >= 303ms && now < 700ms) valve_open_while_held |= machine.bank.mask() != 0;
  };
  machine.clock.stop_at = 1s;
  machine.driver.run(machine.clock.stop.get_token());

  EXPECT_FALSE(valve_open_while_held);
  EXPECT_EQ(machine.driver.stats().holds, 1U);
  EXPECT_EQ(machine.driver.stats().deadman_expiries, 0U);
  std::size_t beats_while_held = 0, opened_after = 0;
  for (const auto& w : machine.heartbeat.history())
    if (w.time > 310ms && w.time < 690ms) ++beats_while_held;
  for (const auto& w : machine.bank.history())
    if (w.mask != 0 && w.time > 700ms) ++opened_after;
  EXPECT_GT(beats_while_held, 20U) << "the relay keeps power: the valves reopen after the fault";
  EXPECT_GT(opened_after, 3U);
}

// The hold's setter writes the valves safe itself; a valve write of this thread already on
// its way lands after that safe write. The driver goes round its loop after each write, finds
// the hold and writes the valves safe before it sleeps.
class RacingBank final : public DigitalOutputBank {
 public:
  RacingBank(sim::MemoryOutputBank& inner, std::atomic<bool>& hold) : inner_(inner), hold_(hold) {}
  std::size_t size() const noexcept override { return inner_.size(); }
  int write(std::uint32_t mask) noexcept override {
    if (mask != 0 && race_armed.exchange(false)) {
      hold_.store(true);    // the E-stop's latch ...
      inner_.force_safe();  // ... and its safe write, just before this write lands
      raced = true;
    }
    return inner_.write(mask);
  }
  int force_safe() noexcept override { return inner_.force_safe(); }
  std::uint32_t safe_mask() const noexcept override { return inner_.safe_mask(); }
  std::atomic<bool> race_armed{false};
  bool raced = false;

 private:
  sim::MemoryOutputBank& inner_;
  std::atomic<bool>& hold_;
};

TEST(ValvePwmDriver, AValveWriteRacingTheHoldIsUndoneBeforeTheDriverSleeps) {
  ScriptedClock clock;
  sim::MemoryOutputBank memory{4, 0, clock, 100000};
  std::atomic<bool> hold{false};
  RacingBank bank(memory, hold);
  control::PwmConfig pwm_config{};
  control::PwmSchedule schedule{pwm_config};
  ValvePwmDriverConfig config;
  config.command_expiry = 10s;
  config.hold_safe = &hold;
  ValvePwmDriver<control::PwmSchedule> driver(clock, bank, schedule, config);
  driver.command(Rig::command(0ns));
  bool open_after_race = false;
  int sleeps_after_race = 0;
  clock.on_sleep = [&](nanoseconds now) {
    if (now >= 200ms && !bank.raced) bank.race_armed = true;
    if (bank.raced && ++sleeps_after_race == 1) open_after_race = memory.mask() != 0;
  };
  clock.stop_at = 400ms;
  driver.run(clock.stop.get_token());

  ASSERT_TRUE(bank.raced) << "the race was not reached";
  EXPECT_FALSE(open_after_race) << "a valve was left open behind the hold's safe write";
  for (const auto& w : memory.history()) {
    if (w.time > 200ms + config.max_sleep) {
      EXPECT_EQ(w.mask, 0U) << "at " << w.time.count();
    }
  }
}

}  // namespace
}  // namespace weedspray::io
