// The gpio-sim side of the board's lines, through sysfs (/sys/devices/platform/DEV/CHIP):
// `sim_gpioN/value` is what the consumer drives (or the pull when no one drives the line),
// `sim_gpioN/pull` makes the edges an input sees. Descriptors are opened once; each read or
// pulse is one pread/pwrite.
#pragma once

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

class SimInputLine {  // a line the daemon reads: make pulses with the pull
 public:
  SimInputLine(const std::string& chip_dir, int offset);
  ~SimInputLine();
  SimInputLine(const SimInputLine&) = delete;
  SimInputLine& operator=(const SimInputLine&) = delete;
  void pulse();  // pull-up then pull-down: one rising and one falling edge

 private:
  void write_pull(bool up);
  int fd_ = -1;
};

}  // namespace weedspray::hil
