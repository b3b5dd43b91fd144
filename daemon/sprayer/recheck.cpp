// SPDX-License-Identifier: Apache-2.0
// The headland re-check's share of a control cycle: when the boom may be re-checked, and the
// step's readings into the cycle's status (control/nozzle_recheck.hpp says how it reads).
#include <cmath>

#include "daemon/sprayer/loop_time.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {

using loop_time::from_seconds;
using loop_time::seconds;

namespace {

// The reading is taken only with the line within this share of its set-point (one nozzle
// alone moves the pressure until the loop has caught up).
constexpr double kPressureTolerance = 0.1;

}  // namespace

bool Sprayer::step_recheck(RecheckWindow& window, Nanos now, bool spray,
                           std::span<const double> target_flow, const PressureStatus& pressure,
                           const LiveParams& params, ControlStatus& status,
                           std::array<control::NozzleLine, io::kMaxValves>& scaled_lines) noexcept {
  const std::size_t nozzles = nozzle_owner_.size();
  // Clear: spraying is on with fresh inputs, no nozzle has anything to spray, every camera
  // sees, every nozzle has a metered held-open flow to be read against, and either no crop is
  // under the boom or the vehicle stands (the start of a job, a stop at the headland).
  bool quiet = spray;
  bool crop = false;
  bool calibrated = true;
  for (std::size_t n = 0; n < nozzles; ++n) {
    if (target_flow[n] > 0.0) quiet = false;
    if (status.crop_density[n] > 0.0) crop = true;
    if (!(params.lines[n].full_open_flow_l_per_min > 0.0)) calibrated = false;
  }
  for (std::size_t c = 0; c < camera_count_; ++c)
    if (cameras_[c].vision_failed) quiet = false;
  const bool stopped = status.speed_m_per_s < config_.nozzle_health.recheck_stopped_m_per_s;
  const bool clear = quiet && calibrated && (stopped || !crop);
  if (!clear) {
    window.clear_since = Nanos{-1};
  } else if (window.clear_since < Nanos{0}) {
    window.clear_since = now;
  }
  control::RecheckInput in;
  in.now_s = seconds(now);
  in.window =
      clear && now - window.clear_since >= from_seconds(config_.nozzle_health.recheck_clear_s);
  in.pressure_ok = spray && std::abs(pressure.pressure_mpa - params.setpoint_mpa) <=
                                kPressureTolerance * params.setpoint_mpa;
  in.meter_pulses = status.flow_pulses;
  in.pulses_per_litre = params.flow_pulses_per_litre;
  in.pressure_mpa = pressure.pressure_mpa;
  // Read against the calibrated lines, never the rescaled ones (the ratio is the calibration's).
  recheck_->step(in, std::span<const control::NozzleLine>(params.lines.data(), nozzles));
  for (std::size_t n = 0; n < nozzles; ++n) {
    scaled_lines[n] = control::scaled_line(params.lines[n], recheck_->scale(n));
    status.recheck_ratio[n] = recheck_->ratio(n);
  }
  status.recheck_warned = recheck_->warned_nozzle();
  status.recheck_alarmed = recheck_->alarmed_nozzle();
  status.recheck_holding = recheck_->overriding();
  status.rechecks = recheck_->completed();
  return recheck_->overriding();
}

}  // namespace weedspray::daemon
