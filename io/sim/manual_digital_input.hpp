// SPDX-License-Identifier: Apache-2.0
// A simulated start/stop key: set by a test or a simulated operator, read like the debounced
// hardware input.
#pragma once

#include "io/clock.hpp"
#include "io/digital_input.hpp"
#include "io/latest_value.hpp"

namespace weedspray::io::sim {

class ManualDigitalInput final : public DigitalInput {
 public:
  explicit ManualDigitalInput(const Clock& clock, bool initial = false) noexcept : clock_(clock) {
    DigitalInputSample s;
    s.active = initial;
    s.time = clock.now();
    published_.publish(s);
  }

  DigitalInputSample sample() const noexcept override { return published_.read(); }

  // One writer: the test or the simulated operator.
  void set(bool active) noexcept {
    DigitalInputSample s = published_.read();
    if (s.active == active) return;
    s.active = active;
    s.time = clock_.now();
    ++s.change_count;
    published_.publish(s);
  }

 private:
  const Clock& clock_;
  LatestValue<DigitalInputSample> published_;
};

}  // namespace weedspray::io::sim
