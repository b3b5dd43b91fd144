// SPDX-License-Identifier: Apache-2.0
// What a simulated world adds to a run, behind one interface so the main loop has no branch
// for it: the world advanced each tick (the vehicle's motion, faults due), faults on request,
// and its ground truth written at exit. This base is hardware mode's: the machine is the world
// and there is nothing to drive. pick_backends() chooses the driver with the backends.
#pragma once

#include <functional>
#include <string>

#include "daemon/bus/status.hpp"

namespace weedspray::daemon {

class WorldDriver {
 public:
  virtual ~WorldDriver() = default;

  // The run starts from nothing: the last run's totals and its unfinished end are not carried on.
  virtual bool starts_afresh() const noexcept { return false; }
  // D-Bus could not be reached (`why`): true when the run goes on without it (said in the log),
  // false when it fails.
  virtual bool runs_without_bus(const char* /*why*/) { return false; }
  // The tank's level sensor is read whatever modbus.enabled says.
  virtual bool tank_always_read() const noexcept { return false; }
  // A camera takes a frame each time the vehicle has moved one footprint: the alarms expect
  // frames at that interval.
  virtual bool frames_per_footprint() const noexcept { return false; }
  // The volume the world truly delivered so far, in litres (a catch test's catch); empty: none.
  virtual std::function<double()> delivered_litres() const { return {}; }

  // Before the loops start: the world at time 0.
  virtual void start() {}
  // Each main-loop tick: the world at t_s seconds after the start, the faults due injected.
  virtual void step(double /*t_s*/) {}
  // A fault by name, now (the InjectSimFault command).
  virtual CommandResult inject_fault(const std::string& /*name*/) {
    return {kErrorNotPermitted, "InjectSimFault: only a simulation (--sim) takes faults"};
  }
  // A status snapshot was published at t_s seconds.
  virtual void status_published(const Status& /*status*/, double /*t_s*/) {}
  // At exit, with the outputs written safe: what the world saw, for the tests.
  virtual void finish() {}
};

}  // namespace weedspray::daemon
