// SPDX-License-Identifier: Apache-2.0
// A CPU wake-up latency request through the kernel's PM QoS interface (/dev/cpu_dma_latency):
// while the file stays open with a 32-bit value written to it, the cpuidle governor keeps every
// CPU out of idle states whose exit latency exceeds that many microseconds. A real-time loop
// on an idle machine otherwise wakes late: measured on these VMs (cpuidle driver haltpoll),
// `weedsprayd --sim` missed ~690 deadlines a minute without a request and ~35 with 0 us.
// On a Raspberry Pi, 0 keeps the cores in WFI (no deeper PSCI states), which costs little power.
// The request ends when the object is destroyed (or the process dies: the kernel closes it).
#pragma once

#include <string>

namespace weedspray::io::hw {

class CpuLatencyRequest {
 public:
  CpuLatencyRequest() = default;
  // Opens `path` and writes `max_latency_us`. Never throws: on failure (no permission - the
  // file is root-only unless a udev rule opens it to a group - or no such file) the request is
  // not active and error() says why.
  explicit CpuLatencyRequest(int max_latency_us, const std::string& path = "/dev/cpu_dma_latency");
  ~CpuLatencyRequest();
  CpuLatencyRequest(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest& operator=(CpuLatencyRequest&& other) noexcept;
  CpuLatencyRequest(const CpuLatencyRequest&) = delete;
  CpuLatencyRequest& operator=(const CpuLatencyRequest&) = delete;

  bool active() const noexcept { return fd_ >= 0; }
  const std::string& error() const noexcept { return error_; }

 private:
  int fd_ = -1;
  std::string error_;
};

}  // namespace weedspray::io::hw
