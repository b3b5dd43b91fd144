// SPDX-License-Identifier: Apache-2.0
#include "daemon/sprayer/calibrations.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <span>

namespace weedspray::daemon {
namespace {

CommandResult refused(const char* method, const std::string& why) {
  return {kErrorNotPermitted, std::string(method) + " refused: " + why};
}

}  // namespace

Calibrations::Calibrations(const Config& config, const std::filesystem::path& state_dir,
                           std::function<double()> sim_delivered_l)
    : file_(state_dir / "calibration.toml"),
      sim_delivered_l_(std::move(sim_delivered_l)),
      run_(static_cast<std::size_t>(config.boom.nozzles)),
      nozzles_(std::min(static_cast<std::size_t>(config.boom.nozzles), io::kMaxValves)) {
  std::string error;
  stored_ = load_calibration(file_, &error);
  if (!error.empty()) spdlog::warn("calibration not restored, the configuration's used: {}", error);
  set_config(config);
  if (stored_.meter) {
    spdlog::info("flow meter: {:.1f} pulses/L from the catch test in {} (configured {:.1f})",
                 stored_.meter->pulses_per_litre, file_.string(), configured_pulses_per_litre_);
  }
  for (std::size_t i = 0; i < nozzles_; ++i) {
    if (choices_[i].source == LineSource::kConfig) continue;
    spdlog::info("nozzle {}: line {} (R^2 {:.4f})", i, to_string(choices_[i].source),
                 choices_[i].r_squared);
  }
}

void Calibrations::set_config(const Config& config) {
  configured_line_.slope_l_per_min_per_pct = config.spray.calibration_slope_l_per_min_per_pct;
  configured_line_.intercept_l_per_min = config.spray.calibration_offset_l_per_min;
  configured_line_.calibration_pressure_mpa = config.spray.calibration_pressure_mpa;
  configured_pulses_per_litre_ = config.flow.pulses_per_litre;
  section_ = config.calibration;
  refresh_choices();
}

void Calibrations::refresh_choices() {
  choose_nozzle_lines(configured_line_, stored_, section_.min_r_squared,
                      std::span(choices_.data(), nozzles_));
}

CommandResult Calibrations::start_catch_test(double seconds, const CalibrationContext& context) {
  if (!context.idle)
    return refused("StartCatchTest", "calibrations run in Idle, not while spraying");
  if (!context.have_meter) return refused("StartCatchTest", "no flow meter is wired");
  const std::string error = run_.start_catch_test(seconds, context.now_s, context.pulses);
  if (!error.empty()) {
    return {run_.running() ? kErrorNotPermitted : kErrorInvalidArgument,
            "StartCatchTest refused: " + error};
  }
  if (sim_delivered_l_) catch_test_delivered_at_start_l_ = sim_delivered_l_();
  spdlog::info("catch test started: every valve open for {:.0f} s", seconds);
  return {};
}

CommandResult Calibrations::calibrate_meter(double volume_l) {
  std::string error;
  const auto result = run_.enter_volume(volume_l, configured_pulses_per_litre_,
                                        section_.meter_max_change_pct, error);
  if (!result) {
    return {run_.state() == CalibrationState::kAwaitingVolume ? kErrorInvalidArgument
                                                              : kErrorNotPermitted,
            "CalibrateMeter refused: " + error};
  }
  stored_.meter = *result;
  save();
  spdlog::info("flow meter calibrated: {}", run_.message());
  return {};
}

CommandResult Calibrations::calibrate_nozzles(const CalibrationContext& context) {
  if (!context.idle)
    return refused("CalibrateNozzles", "calibrations run in Idle, not while spraying");
  if (!context.have_meter) return refused("CalibrateNozzles", "no flow meter is wired");
  NozzleSweepPlan plan;
  plan.duties_pct = section_.duties_pct;
  plan.settle_s = section_.settle_s;
  plan.measure_s = section_.measure_s;
  plan.full_open = section_.full_open;
  plan.pressure_mpa = context.setpoint_mpa;
  plan.pulses_per_litre = meter_pulses_per_litre(configured_pulses_per_litre_, stored_);
  const std::string error = run_.start_nozzle_sweep(plan, context.now_s, context.pulses);
  if (!error.empty()) return refused("CalibrateNozzles", error);
  spdlog::info("nozzle calibration started: {} nozzles x {} duties at {:.3f} MPa", nozzles_,
               plan.duties_pct.size(), plan.pressure_mpa);
  return {};
}

CommandResult Calibrations::test_valve(std::uint32_t nozzle, double duty_pct, double seconds,
                                       const CalibrationContext& context) {
  if (!context.idle) return refused("TestValve", "tests run in Idle, not while spraying");
  const double k =
      context.have_meter ? meter_pulses_per_litre(configured_pulses_per_litre_, stored_) : 0.0;
  const std::string error =
      run_.start_valve_test(nozzle, duty_pct, seconds, context.now_s, context.pulses, k);
  if (!error.empty()) return refused("TestValve", error);
  spdlog::info("{}", run_.message());
  return {};
}

CommandResult Calibrations::test_pump(double seconds, const CalibrationContext& context) {
  if (!context.idle) return refused("TestPump", "tests run in Idle, not while spraying");
  const std::string error = run_.start_pump_test(seconds, context.now_s, context.setpoint_mpa);
  if (!error.empty()) return refused("TestPump", error);
  spdlog::info("{}", run_.message());
  return {};
}

bool Calibrations::cancel(const char* why) {
  const CalibrationState before = run_.state();
  run_.cancel(why);
  if (run_.state() == before) return false;
  spdlog::info("calibration {}", run_.message());
  return true;
}

bool Calibrations::update(const CalibrationContext& context) {
  if (!run_.running()) return false;
  if (!context.idle) {
    cancel("the sprayer left Idle");
    return true;
  }
  const CalibrationState before = run_.state();
  const auto duties = run_.duties();
  run_.observe_pressure(context.now_s, context.pressure_mpa);
  run_.update(context.now_s, context.pulses);
  if ((before == CalibrationState::kValveTest || before == CalibrationState::kPumpTest) &&
      run_.state() == CalibrationState::kDone) {
    spdlog::info("{}", run_.message());
    return true;
  }
  if (before == CalibrationState::kCatchTest && run_.state() == CalibrationState::kAwaitingVolume) {
    spdlog::info("{}", run_.message());
    if (sim_delivered_l_) {
      spdlog::info(
          "sim: the catch test delivered {:.5f} L (the plant's truth: the volume to enter)",
          sim_delivered_l_() - catch_test_delivered_at_start_l_);
    }
  }
  if (before == CalibrationState::kNozzles && run_.state() == CalibrationState::kDone) {
    auto fits = run_.take_fits();
    stored_.nozzles.resize(std::max(stored_.nozzles.size(), fits.size()));
    for (std::size_t i = 0; i < fits.size(); ++i) {
      if (fits[i]) {
        stored_.nozzles[i] = fits[i];
        spdlog::info(
            "nozzle {}: q = {:.5f} s + {:.4f} L/min at {:.3f} MPa, R^2 {:.4f}, held open {:.4f} "
            "L/min{}",
            i, fits[i]->line.slope_l_per_min_per_pct, fits[i]->line.intercept_l_per_min,
            fits[i]->line.calibration_pressure_mpa, fits[i]->r_squared,
            fits[i]->line.full_open_flow_l_per_min,
            fits[i]->line.full_open_flow_l_per_min > 0 ? "" : " (not measured: unknown)");
      } else {
        spdlog::warn("nozzle {}: no line could be fitted (no flow?); its previous line stays", i);
      }
    }
    refresh_choices();
    save();
    spdlog::info("{}", run_.message());
    return true;
  }
  return run_.duties() != duties;
}

void Calibrations::apply(LiveParams& params) const {
  params.flow_pulses_per_litre = meter_pulses_per_litre(configured_pulses_per_litre_, stored_);
  for (std::size_t i = 0; i < nozzles_; ++i) params.lines[i] = choices_[i].line;
  params.calibration_valves = run_.running();
  params.calibration_duty_pct = run_.duties();
}

void Calibrations::fill_status(Status& s) const {
  s.calibration_state = to_string(run_.state());
  s.calibration_progress = run_.progress();
  s.calibration_message = run_.message();
  s.meter_source = stored_.meter ? "calibration" : "config";
  s.meter_pulses_per_litre = meter_pulses_per_litre(configured_pulses_per_litre_, stored_);
  s.meter_configured_pulses_per_litre = configured_pulses_per_litre_;
  s.meter_error_pct = stored_.meter ? stored_.meter->error_pct : 0.0;
  s.nozzle_lines.clear();
  for (std::size_t i = 0; i < nozzles_; ++i) {
    const NozzleLineChoice& c = choices_[i];
    s.nozzle_lines.push_back({to_string(c.source), c.line.slope_l_per_min_per_pct,
                              c.line.intercept_l_per_min, c.r_squared});
  }
}

void Calibrations::save() noexcept {
  try {
    std::filesystem::create_directories(file_.parent_path());
    save_calibration(file_, stored_);
    spdlog::info("calibration saved in {}", file_.string());
  } catch (const std::exception& error) {
    spdlog::error("calibration not saved (in use until the daemon stops): {}", error.what());
  }
}

}  // namespace weedspray::daemon
