// SPDX-License-Identifier: Apache-2.0
// io::hw::CounterPulseInput against a fake /sys/bus/counter tree in a temp dir (no kernel
// counter needed); the real interrupt-cnt driver is exercised in the QEMU harness (tests/vm).
#include <fcntl.h>
#include <grp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "io/linux/counter_pulse_input.hpp"
#include "io/linux/monotonic_clock.hpp"

extern char** environ;

namespace weedspray::io::hw {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using ::testing::HasSubstr;

constexpr auto kPoll = 1ms;
constexpr auto kWaitLimit = 5s;

// Waits until `done(snapshot)` holds or kWaitLimit passes; returns the last snapshot.
template <class Predicate>
PulseSnapshot wait_until(const PulseInput& input, Predicate done) {
  const auto deadline = monotonic_now() + kWaitLimit;
  PulseSnapshot s = input.snapshot();
  while (!done(s) && monotonic_now() < deadline) {
    std::this_thread::sleep_for(200us);
    s = input.snapshot();
  }
  return s;
}

// A fake counter tree: counter0 named "flow-counter" with count0 (count + enable), counter1
// named "wheel-counter" with count0 and count1.
class FakeCounter : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/weedspray-counter-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    root_ = tmpl;
    make_counter("counter0", "flow-counter", 1);
    make_counter("counter1", "wheel-counter", 2);
  }
  void TearDown() override { fs::remove_all(root_); }

  void make_counter(const std::string& dir, const std::string& name, int counts) {
    fs::create_directories(root_ / dir);
    put(root_ / dir / "name", name + "\n");
    for (int i = 0; i < counts; ++i) {
      const fs::path count_dir = root_ / dir / ("count" + std::to_string(i));
      fs::create_directories(count_dir);
      put(count_dir / "count", fixed_width(1000));
      put(count_dir / "enable", "1\n");
    }
  }
  static void put(const fs::path& p, const std::string& text) { std::ofstream(p) << text; }
  static std::string get(const fs::path& p) {
    std::ifstream in(p);
    std::string s;
    std::getline(in, s);
    return s;
  }
  static std::string fixed_width(std::uint64_t value) {
    char text[32];
    std::snprintf(text, sizeof(text), "%020llu\n", static_cast<unsigned long long>(value));
    return text;
  }

  // The class reads `count` on its own thread while the test changes it. A change of more than
  // one byte could be read half-written, which real sysfs never shows; so every change here
  // rewrites exactly one byte in place (a one-byte store is seen whole or not at all).
  static void change_one_byte(const fs::path& p, const std::string& new_text) {
    const std::string old_text = get(p) + "\n";
    ASSERT_EQ(old_text.size(), new_text.size());
    std::size_t differing = 0, at = 0;
    for (std::size_t i = 0; i < new_text.size(); ++i)
      if (old_text[i] != new_text[i]) ++differing, at = i;
    ASSERT_EQ(differing, 1U) << old_text << " -> " << new_text;
    const int fd = ::open(p.c_str(), O_WRONLY);
    ASSERT_GE(fd, 0);
    EXPECT_EQ(::pwrite(fd, &new_text[at], 1, static_cast<off_t>(at)), 1);
    ::close(fd);
  }
  void set_count(std::uint64_t value) { change_one_byte(count0_, fixed_width(value)); }

  CounterPulseInputConfig config(const std::string& device, int count_index = 0) const {
    return {.device = device,
            .count_index = count_index,
            .poll_period = kPoll,
            .sysfs_root = root_.string()};
  }

  fs::path root_;
  fs::path count0_ = "";  // set by tests that use set_count
};

TEST_F(FakeCounter, CountsPulsesSinceStartAndStampsThePollThatSawThem) {
  count0_ = root_ / "counter0/count0/count";
  CounterPulseInput flow(config("flow-counter"));
  EXPECT_EQ(flow.count_path(), count0_.string());
  std::this_thread::sleep_for(20 * kPoll);
  PulseSnapshot s = flow.snapshot();
  EXPECT_EQ(s.count, 0U) << "the kernel's 1000 at start are not pulses of this run";
  EXPECT_EQ(s.last_edge_time.count(), 0);

  std::chrono::nanoseconds previous_poll{0};
  for (const std::uint64_t raw : {1007U, 1037U, 1537U}) {
    const auto before = monotonic_now();
    set_count(raw);
    s = wait_until(flow, [&](const PulseSnapshot& p) { return p.count == raw - 1000; });
    const auto after = monotonic_now();
    ASSERT_EQ(s.count, raw - 1000);
    EXPECT_GE(s.last_edge_time, before);
    EXPECT_LE(s.last_edge_time, after);
    EXPECT_GT(s.last_edge_time, previous_poll);
    previous_poll = s.last_edge_time;
  }
  std::this_thread::sleep_for(20 * kPoll);
  s = flow.snapshot();
  EXPECT_EQ(s.count, 537U) << "no count without a change";
  EXPECT_EQ(s.last_edge_time, previous_poll) << "the stamp moves only when the count does";
  EXPECT_EQ(s.error_count, 0U);
  EXPECT_EQ(s.overflow_count, 0U);
}

TEST_F(FakeCounter, WritesEnableWhenTheCounterIsOff) {
  put(root_ / "counter0/count0/enable", "0\n");
  CounterPulseInput flow(config("flow-counter"));
  EXPECT_EQ(get(root_ / "counter0/count0/enable"), "1");
}

TEST_F(FakeCounter, FindsTheCounterByDirectoryOrPathAndCountIndex) {
  count0_ = root_ / "counter1/count1/count";
  {
    CounterPulseInput by_dir(config("counter1", 1));
    EXPECT_EQ(by_dir.count_path(), count0_.string());
  }
  CounterPulseInput by_path(config((root_ / "counter1").string(), 1));
  set_count(1009);
  EXPECT_EQ(wait_until(by_path, [](const PulseSnapshot& p) { return p.count == 9; }).count, 9U);
}

TEST_F(FakeCounter, GarbageCountsErrorsUntilTheValueIsValidAgain) {
  count0_ = root_ / "counter0/count0/count";
  CounterPulseInput flow(config("flow-counter"));
  std::string text = fixed_width(1000);
  text[text.size() - 2] = 'x';  // "...100x\n"
  change_one_byte(count0_, text);
  PulseSnapshot s = wait_until(flow, [](const PulseSnapshot& p) { return p.error_count > 0; });
  EXPECT_GT(s.error_count, 0U);
  EXPECT_EQ(s.count, 0U);

  set_count(1003);
  s = wait_until(flow, [](const PulseSnapshot& p) { return p.count == 3; });
  EXPECT_EQ(s.count, 3U) << "counted from the last valid value";
  const std::uint64_t errors = s.error_count;
  std::this_thread::sleep_for(20 * kPoll);
  EXPECT_EQ(flow.snapshot().error_count, errors) << "valid reads add no error";
}

// A removed sysfs attribute fails every read on its open fd (ENODEV). The same happens to
// /proc/PID/oom_score once PID is gone (ESRCH), so that file stands in for `count`.
TEST_F(FakeCounter, ReadsFailingAfterStartCountErrorsWithoutThrowing) {
  pid_t child = 0;
  char sleep_program[] = "sleep";
  char seconds[] = "60";
  char* argv[] = {sleep_program, seconds, nullptr};
  ASSERT_EQ(posix_spawnp(&child, "sleep", nullptr, nullptr, argv, environ), 0);
  fs::create_directories(root_ / "counter2/count0");
  put(root_ / "counter2/name", "vanishing\n");  // and no `enable`: such counters always count
  fs::create_symlink("/proc/" + std::to_string(child) + "/oom_score",
                     root_ / "counter2/count0/count");

  CounterPulseInput input(config("vanishing"));
  std::this_thread::sleep_for(20 * kPoll);
  EXPECT_EQ(input.snapshot().error_count, 0U) << "readable while the process lives";
  ASSERT_EQ(kill(child, SIGKILL), 0);
  ASSERT_EQ(waitpid(child, nullptr, 0), child);
  const PulseSnapshot s =
      wait_until(input, [](const PulseSnapshot& p) { return p.error_count > 1; });
  EXPECT_GT(s.error_count, 1U) << "every poll of the vanished file is an error";
}

TEST_F(FakeCounter, MissingCounterOrCountIsAClearError) {
  try {
    CounterPulseInput input(config("no-such-counter"));
    ADD_FAILURE() << "no error for a missing counter";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("'no-such-counter' not found under " + root_.string()));
    EXPECT_THAT(e.what(), HasSubstr("interrupt-cnt"));
  }
  try {
    CounterPulseInput input(config("flow-counter", 3));
    ADD_FAILURE() << "no error for a missing count3";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr((root_ / "counter0/count3/count").string() +
                                    ": No such file or directory"));
  }
  put(root_ / "counter0/count0/count", "garbage\n");
  try {
    CounterPulseInput input(config("flow-counter"));
    ADD_FAILURE() << "no error for a count that is not a number";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("does not hold a decimal count"));
  }
}

TEST_F(FakeCounter, ANameSharedByTwoCountersIsRefused) {
  make_counter("counter5", "flow-counter", 1);
  try {
    CounterPulseInput input(config("flow-counter"));
    ADD_FAILURE() << "no error for an ambiguous name";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("configure the directory instead"));
  }
}

// The daemon does not run as root: a counter it may not enable must say so and point at the
// udev rule. Run in a child that gives up root (as root, file modes do not stop a write).
TEST_F(FakeCounter, EnableRefusedNamesThePathTheErrorAndTheUdevRule) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const fs::path enable = root_ / "counter0/count0/enable";
  put(enable, "0\n");
  fs::permissions(enable, fs::perms::owner_read | fs::perms::group_read | fs::perms::others_read);
  fs::permissions(root_, fs::perms::owner_all | fs::perms::group_read | fs::perms::group_exec |
                             fs::perms::others_read | fs::perms::others_exec);
  const CounterPulseInputConfig flow_config = config("flow-counter");
  EXPECT_EXIT(
      {
        if (geteuid() == 0) {
          constexpr gid_t kNobody = 65534;
          if (setgroups(0, nullptr) != 0 || setgid(kNobody) != 0 || setuid(kNobody) != 0)
            std::_Exit(4);
        }
        try {
          CounterPulseInput input(flow_config);
        } catch (const std::runtime_error& e) {
          std::fputs(e.what(), stderr);
          std::_Exit(3);
        }
        std::_Exit(0);
      },
      ::testing::ExitedWithCode(3),
      "cannot open .*counter0/count0/enable: Permission denied.*udev.*60-weedspray.rules");
  EXPECT_EQ(get(enable), "0");
}

TEST(CounterValue, ParsesSysfsUnsignedDecimalsOnly) {
  std::uint64_t v = 7;
  EXPECT_TRUE(parse_counter_value("123\n", v));
  EXPECT_EQ(v, 123U);
  EXPECT_TRUE(parse_counter_value("18446744073709551615\n", v));
  EXPECT_EQ(v, std::numeric_limits<std::uint64_t>::max());
  EXPECT_TRUE(parse_counter_value("0", v));
  EXPECT_EQ(v, 0U);
  for (const char* bad : {"", "\n", "12x\n", "-1\n", " 1\n", "1\n\n", "18446744073709551616\n"})
    EXPECT_FALSE(parse_counter_value(bad, v)) << "'" << bad << "'";
}

TEST(CounterTotal, CountsChangesFromTheFirstValue) {
  CounterTotal total(1000);
  EXPECT_EQ(total.update(1000), CounterTotal::Change::kNone);
  EXPECT_EQ(total.update(1005), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.update(1005), CounterTotal::Change::kNone);
  EXPECT_EQ(total.update(1105), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.count(), 105U);
}

// interrupt-cnt keeps an int and sign-extends it into the u64 sysfs value.
TEST(CounterTotal, FollowsInterruptCntsSignExtendedWrapAndTheU64Wrap) {
  CounterTotal total(2147483646U);
  EXPECT_EQ(total.update(2147483647U), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.update(18446744071562067968ULL), CounterTotal::Change::kCounted);  // INT_MIN
  EXPECT_EQ(total.update(18446744073709551615ULL), CounterTotal::Change::kCounted);  // -1
  EXPECT_EQ(total.update(0), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.update(3), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.count(), 1U + 1U + 2147483647U + 1U + 3U);
}

TEST(CounterTotal, AJumpBelowTwoToThe31CountsAndABackwardStepResynchronises) {
  CounterTotal total(1000);
  const std::uint64_t far = 1000 + 2147483647ULL;  // the largest jump read as pulses
  EXPECT_EQ(total.update(far), CounterTotal::Change::kCounted);
  EXPECT_EQ(total.count(), 2147483647U);
  EXPECT_EQ(total.update(far - 647), CounterTotal::Change::kWentBackwards);
  EXPECT_EQ(total.count(), 2147483647U) << "nothing counted";
  EXPECT_EQ(total.update(far - 644), CounterTotal::Change::kCounted) << "counts from there";
  EXPECT_EQ(total.count(), 2147483650U);

  CounterTotal reset(5000);
  EXPECT_EQ(reset.update(0), CounterTotal::Change::kWentBackwards) << "count written to 0";
  EXPECT_EQ(reset.update(2), CounterTotal::Change::kCounted);
  EXPECT_EQ(reset.count(), 2U);
}

}  // namespace
}  // namespace weedspray::io::hw
