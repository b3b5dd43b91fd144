// SPDX-License-Identifier: Apache-2.0
#include "control/pressure_controller.hpp"

namespace weedspray::control {
namespace {

std::variant<Pid, FuzzyPid> make_controller(PressureControlMode mode,
                                            const FuzzyPidConfig& config) {
  if (mode == PressureControlMode::kFuzzyPid) return FuzzyPid(config);
  return Pid(config.base);
}

}  // namespace

PressureController::PressureController(PressureControlMode mode, const FuzzyPidConfig& config)
    : mode_(mode), controller_(make_controller(mode, config)) {}

double PressureController::update(double setpoint, double measurement, double dt_s) noexcept {
  return std::visit([&](auto& c) { return c.update(setpoint, measurement, dt_s); }, controller_);
}

void PressureController::enable(double current_output, double setpoint,
                                double measurement) noexcept {
  std::visit([&](auto& c) { c.enable(current_output, setpoint, measurement); }, controller_);
}

void PressureController::disable() noexcept {
  std::visit([](auto& c) { c.disable(); }, controller_);
}

bool PressureController::enabled() const noexcept {
  return std::visit([](const auto& c) { return c.enabled(); }, controller_);
}

void PressureController::reset() noexcept {
  std::visit([](auto& c) { c.reset(); }, controller_);
}

double PressureController::output() const noexcept {
  return std::visit([](const auto& c) { return c.output(); }, controller_);
}

PidGains PressureController::current_gains() const noexcept {
  if (const auto* fuzzy = std::get_if<FuzzyPid>(&controller_)) return fuzzy->current_gains();
  return std::get<Pid>(controller_).gains();
}

const PidTerms& PressureController::last_terms() const noexcept {
  return std::visit([](const auto& c) -> const PidTerms& { return c.last_terms(); }, controller_);
}

}  // namespace weedspray::control
