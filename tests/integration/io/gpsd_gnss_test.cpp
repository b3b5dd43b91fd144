// SPDX-License-Identifier: Apache-2.0
// The gpsd client (io/linux/gpsd_gnss.hpp) against a real gpsd fed by gpsfake (Debian's gpsd and
// gpsd-clients) on a private port, with the project's recorded track (tools/gnss/make_track.py:
// a straight run, a 90-degree turn, braking to a stop). It checks that each fix the reader
// returns is the track's epoch of that UTC time (position, speed, course, altitude), that every
// segment came through, that the fix counts as lost once gpsfake (and its gpsd) stops, and that
// the reader reconnects by itself when a gpsd is back on the port.
// gpsd and gpsfake are REQUIRED (./dev deps installs them): SetUp fails, never skips.
#include "io/linux/gpsd_gnss.hpp"

#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "daemon/sprayer/ground_speed.hpp"
#include "io/linux/monotonic_clock.hpp"
#include "tests/integration/io/modbus_peer.hpp"

namespace weedspray::io::hw {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

const fs::path kTrackDir = fs::path(WEEDSPRAY_SOURCE_DIR) / "tests/data/gnss";

struct Epoch {
  double lat, lon, alt, speed, course;
  std::string segment;
};

// field_track.csv: UTC time (ns since 1970) -> the epoch the NMEA sentences describe.
std::map<std::int64_t, Epoch> read_track() {
  std::map<std::int64_t, Epoch> track;
  std::ifstream in(kTrackDir / "field_track.csv");
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string utc, lat, lon, alt, speed, course, segment;
    std::getline(fields, utc, ',');
    std::getline(fields, lat, ',');
    std::getline(fields, lon, ',');
    std::getline(fields, alt, ',');
    std::getline(fields, speed, ',');
    std::getline(fields, course, ',');
    std::getline(fields, segment, ',');
    std::tm tm{};
    if (strptime(utc.c_str(), "%Y-%m-%dT%H:%M:%SZ", &tm) == nullptr) continue;
    const std::int64_t ns = static_cast<std::int64_t>(timegm(&tm)) * 1'000'000'000;
    track[ns] = Epoch{std::stod(lat),   std::stod(lon),    std::stod(alt),
                      std::stod(speed), std::stod(course), segment};
  }
  return track;
}

// A TCP port nobody listens on now (the kernel's pick), for this test's gpsd.
int free_port() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t size = sizeof addr;
  const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
                  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &size) == 0;
  close(fd);
  return ok ? ntohs(addr.sin_port) : -1;
}

// gpsfake playing the track once on `port`, in a process group of its own: stopping it ends its
// gpsd too (killing gpsfake alone would leave its gpsd holding the port).
// -c: 50 ms between sentences; -W: gpsfake (and its gpsd) ends 2 s after the track even if the
// test does not stop it.
std::unique_ptr<test::Child> start_gpsfake(int port, const fs::path& log) {
  return std::make_unique<test::Child>(
      std::vector<std::string>{"/usr/bin/gpsfake", "-1", "-q", "-c", "0.05", "-W", "2", "-P",
                               std::to_string(port), (kTrackDir / "field_track.nmea").string()},
      log, /*own_process_group=*/true);
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

class GpsdPeer : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists("/usr/bin/gpsfake") && fs::exists("/usr/sbin/gpsd"))
        << "gpsd and gpsfake are required (apt-get install gpsd gpsd-clients; ./dev deps "
           "installs them)";
    track_ = read_track();
    ASSERT_EQ(track_.size(), 32U) << "tests/data/gnss/field_track.csv";
    port_ = free_port();
    ASSERT_GT(port_, 0);
    char tmpl[] = "/tmp/weedspray-gpsd-XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  GpsdGnssConfig config() const {
    GpsdGnssConfig c;
    c.host = "127.0.0.1";
    c.port = std::to_string(port_);
    c.first_retry = 50ms;  // the test starts the reader before gpsd is up
    c.max_retry = 200ms;
    return c;
  }

  std::map<std::int64_t, Epoch> track_;
  int port_ = -1;
  fs::path dir_;
};

TEST_F(GpsdPeer, ReadsTheTrackThenLosesTheFixWhenGpsdStopsAndReconnects) {
  GpsdGnss gnss(config());
  MonotonicClock clock;
  const auto timeout = 1s;
  daemon::LostFixWatch lost_fix(clock.now(), timeout, 30s);
  GnssFix fix;
  EXPECT_FALSE(gnss.next_fix(fix, 100ms));  // no gpsd yet: refused, retried later
  EXPECT_GE(gnss.stats().connect_failures, 1U);

  auto gpsfake = start_gpsfake(port_, dir_ / "gpsfake.log");
  ASSERT_TRUE(gpsfake->started());
  const std::int64_t last_epoch = track_.rbegin()->first;
  std::map<std::string, int> per_segment;
  int fixes = 0;
  int untimed = 0;  // fixes without a UTC time
  daemon::GnssSample latest;
  const auto give_up = std::chrono::steady_clock::now() + 20s;
  while (latest.value.utc_ns != last_epoch && std::chrono::steady_clock::now() < give_up) {
    if (!gnss.next_fix(fix, 200ms)) continue;
    latest = daemon::GnssSample{fix, clock.now(), 0};
    if (fix.mode == GnssFixMode::kNone) continue;  // gpsd's first report, before any sentence
    if (fix.utc_ns == 0) {  // a GGA read before any RMC: a time of day without its date
      ++untimed;
      continue;
    }
    ++fixes;
    const auto epoch = track_.find(fix.utc_ns);
    ASSERT_NE(epoch, track_.end()) << "a fix at a time the track does not have: " << fix.utc_ns;
    const Epoch& e = epoch->second;
    SCOPED_TRACE(e.segment + " epoch at +" +
                 std::to_string((fix.utc_ns - track_.begin()->first) / 1'000'000'000) + " s");
    // NMEA carries 6 decimals of a minute (2 mm) and speed in knots to 3 decimals.
    EXPECT_NEAR(fix.latitude_deg, e.lat, 1e-7);
    EXPECT_NEAR(fix.longitude_deg, e.lon, 1e-7);
    // gpsd's first reports of a stream can be partial (a TPV sent before the GGA and GSA of
    // its epoch were read: 2D, no altitude): the mode, altitude and sky view are checked where
    // given, and below on the last fix.
    if (std::isfinite(fix.altitude_m)) {
      EXPECT_NEAR(fix.altitude_m, e.alt, 1e-6);
    }
    EXPECT_NEAR(fix.speed_m_per_s, e.speed, 1e-3);
    if (e.speed > 0) {
      EXPECT_NEAR(fix.course_deg, e.course, 0.05);
    }
    if (fix.satellites_used > 0) {
      EXPECT_EQ(fix.satellites_used, 9U);
    }
    if (std::isfinite(fix.hdop)) {
      EXPECT_NEAR(fix.hdop, 0.8, 1e-9);
    }
    ++per_segment[e.segment];
  }
  EXPECT_LE(untimed, 2) << "only the first reports of a stream may lack the date";
  ASSERT_EQ(latest.value.utc_ns, last_epoch)
      << fixes
      << " fixes; the track's last epoch never came. gpsfake: " << read_text(dir_ / "gpsfake.log");
  // gpsd may fold the first epochs (fed before it opened the pty) into one: the rest each
  // arrive. The turn (10 epochs), the braking (3) and the stop (5) are later in the track.
  EXPECT_GE(per_segment["straight"], 6);
  EXPECT_EQ(per_segment["turn"], 10);
  EXPECT_EQ(per_segment["braking"], 3);
  EXPECT_EQ(per_segment["stop"], 5);
  EXPECT_EQ(latest.value.mode, GnssFixMode::k3D);
  EXPECT_NEAR(latest.value.altitude_m, 12.5, 1e-6);
  EXPECT_EQ(latest.value.satellites_used, 9U);  // from the sky view (GSA + GSV)
  EXPECT_NEAR(latest.value.hdop, 0.8, 1e-9);
  EXPECT_TRUE(daemon::gnss_fix_usable(latest, clock.now(), timeout));
  EXPECT_FALSE(lost_fix.lost(latest, clock.now()));
  EXPECT_TRUE(gnss.stats().connected);
  EXPECT_EQ(gnss.stats().connects, 1U);

  // gpsfake stops, and its gpsd with it: no more fixes, the link reports the loss, and after
  // the timeout the fix counts as lost.
  gpsfake->stop();
  const auto stopped = clock.now();
  while (clock.now() - stopped < timeout + 300ms) {
    EXPECT_FALSE(gnss.next_fix(fix, 100ms) && fix.mode != GnssFixMode::kNone)
        << "a fix after gpsd stopped";
  }
  EXPECT_FALSE(gnss.stats().connected);
  EXPECT_EQ(gnss.stats().disconnects, 1U);
  EXPECT_TRUE(lost_fix.lost(latest, clock.now()));
  EXPECT_FALSE(daemon::gnss_fix_usable(latest, clock.now(), timeout));

  // A gpsd on the port again: the reader reconnects within its backoff and reads fixes.
  const std::uint64_t failures_while_away = gnss.stats().connect_failures;
  gpsfake = start_gpsfake(port_, dir_ / "gpsfake2.log");
  ASSERT_TRUE(gpsfake->started());
  bool again = false;
  const auto give_up_again = std::chrono::steady_clock::now() + 10s;
  while (!again && std::chrono::steady_clock::now() < give_up_again) {
    again = gnss.next_fix(fix, 200ms) && fix.mode == GnssFixMode::k3D;
  }
  EXPECT_TRUE(again) << "no fix after gpsd came back: " << read_text(dir_ / "gpsfake2.log");
  EXPECT_EQ(gnss.stats().connects, 2U);
  EXPECT_GT(failures_while_away, 1U);  // it kept trying while gpsd was away
}

}  // namespace
}  // namespace weedspray::io::hw
