// SPDX-License-Identifier: Apache-2.0
// GNSS through gpsd (Debian's libgps): the daemon is a gpsd client, so any receiver gpsd
// supports works. Blocking (it waits on a socket): only on a worker thread, never on an RT one.
// When gpsd is not there or goes away, next_fix() reconnects with a doubling backoff.
#pragma once

#include <chrono>
#include <memory>
#include <string>

#include "io/gnss.hpp"
#include "io/latest_value.hpp"

namespace weedspray::io::hw {

struct GpsdGnssConfig {
  std::string host = "localhost";
  std::string port = "2947";
  std::chrono::milliseconds first_retry{250};  // after the first failed connection
  std::chrono::milliseconds max_retry{5000};   // the backoff's ceiling
};

class GpsdGnss final : public GnssReceiver {
 public:
  explicit GpsdGnss(GpsdGnssConfig config);
  ~GpsdGnss() override;
  GpsdGnss(const GpsdGnss&) = delete;
  GpsdGnss& operator=(const GpsdGnss&) = delete;

  // One thread only (the GNSS worker).
  bool next_fix(GnssFix& fix, std::chrono::nanoseconds wait) noexcept override;
  // Any thread.
  GnssLinkStats stats() const noexcept override { return stats_.read(); }

 private:
  struct Connection;  // gps_data_t lives in the .cpp: no libgps header here
  using Steady = std::chrono::steady_clock;

  bool connect() noexcept;
  void disconnect() noexcept;
  bool read_until(GnssFix& fix, Steady::time_point deadline) noexcept;

  GpsdGnssConfig config_;
  std::unique_ptr<Connection> connection_;
  bool connected_ = false;
  Steady::time_point next_attempt_{};
  std::chrono::milliseconds retry_{0};
  GnssLinkStats counters_;  // next_fix()'s thread; published into stats_
  LatestValue<GnssLinkStats> stats_;
};

}  // namespace weedspray::io::hw
