// SPDX-License-Identifier: Apache-2.0
// The gpio-sim side of the board's lines, through sysfs (/sys/devices/platform/DEV/CHIP):
// `sim_gpioN/value` is what the consumer drives (or the pull when no one drives the line),
// `sim_gpioN/pull` makes the edges an input sees. Descriptors are opened once; each read or
// pulse is one pread/pwrite.
#pragma once

#include <cstdint>
#include <string>

namespace weedspray::hil {

class SimOutputLine {  // a line the daemon drives: read its level
 public:
  SimOutputLine(const std::string& chip_dir, int offset);
  ~SimOutputLine();
  SimOutputLine(const SimOutputLine&) = delete;
  SimOutputLine& operator=(const SimOutputLine&) = delete;
  bool high() const;  // throws std::runtime_error on a failed read

 private:
  int fd_ = -1;
};

// A line the daemon reads: pulses made with the pull, one edge per call of step(), so the two
// edges of a pulse are a sampling period apart (a sensor's square wave; back-to-back edges
// would be merged by the kernel's threaded edge-event handler, which is not what a wheel does).
class SimInputLine {
 public:
  SimInputLine(const std::string& chip_dir, int offset);
  ~SimInputLine();
  SimInputLine(const SimInputLine&) = delete;
  SimInputLine& operator=(const SimInputLine&) = delete;
  // Makes the next edge toward `wanted` pulses: a rising edge when low and behind (the pulse
  // counts as sent), a falling edge when high.
  void step(std::uint64_t wanted);
  std::uint64_t sent() const { return sent_; }

 private:
  void write_pull(bool up);
  int fd_ = -1;
  bool high_ = false;
  std::uint64_t sent_ = 0;
};

}  // namespace weedspray::hil
