// SPDX-License-Identifier: Apache-2.0
#include "daemon/config/config_schema.hpp"

#include <algorithm>
#include <array>

#include <climits>
#include <sstream>
#include <stdexcept>

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon {

// A captureless accessor for one member, converted to a plain function pointer so the table
// is data, not code.
#define WS_FIELD(Root, member) \
  +[](Root & r) -> auto& {     \
    return r.member;           \
  }
#define WS_KEY(section, name) #section, #name, WS_FIELD(Config, section.name)
#define WS_CAM(name) "camera", #name, WS_FIELD(CameraSection, name)

template <class Root>
KeyType KeySpec<Root>::type() const {
  switch (field.index()) {
    case 0:
      return KeyType::kBool;
    case 1:
      return KeyType::kInt;
    case 2:
      return KeyType::kDouble;
    case 3:
      return choices.empty() ? KeyType::kString : KeyType::kEnum;
    case 4:
      return KeyType::kIntList;
    case 5:
      return KeyType::kStringList;
    default:
      return KeyType::kDoubleList;
  }
}

template <class Root>
std::string KeySpec<Root>::full_name() const {
  return std::string(section) + "." + std::string(name);
}

template struct KeySpec<Config>;
template struct KeySpec<CameraSection>;

std::string_view key_type_name(KeyType type) {
  switch (type) {
    case KeyType::kBool:
      return "boolean";
    case KeyType::kInt:
      return "integer";
    case KeyType::kDouble:
      return "number";
    case KeyType::kString:
      return "string";
    case KeyType::kEnum:
      return "choice";
    case KeyType::kIntList:
      return "array of integers";
    case KeyType::kStringList:
      return "array of strings";
    case KeyType::kDoubleList:
      return "array of numbers";
  }
  return "?";
}

const std::vector<KeySpec<Config>>& config_keys() {
  // clang-format off
  static const std::vector<KeySpec<Config>> keys = {
    // [daemon]
    {WS_KEY(daemon, autostart), false, 0, 1, "",
     "start spraying as soon as the daemon is set up (otherwise wait for Start or the key); "
     "not after a run that did not end in an orderly stop (a crash, kill -9, the watchdog, a "
     "power cut, a lost D-Bus connection): then it waits for Start"},
    {WS_KEY(daemon, log_level), std::string("info"), 0, 0, "",
     "minimum level logged to the journal or console",
     {"trace", "debug", "info", "warn", "error"}},
    {WS_KEY(daemon, state_dir), std::string("/var/lib/weedspray"), 0, 0, "path",
     "persistent state: totals and (by default) the as-applied logs"},
    {WS_KEY(daemon, status_max_rate_hz), 4.0, 0.5, 20, "Hz",
     "D-Bus PropertiesChanged are emitted at most this often"},
    {WS_KEY(daemon, input_stale_timeout_s), 0.5, 0.05, 10, "s",
     "a live input (pressure, vision, wheel) older than this closes the valves"},
    {WS_KEY(daemon, cpu_wakeup_latency_us), 0, -1, 100000, "us",
     "PM QoS request held while the loops run (/dev/cpu_dma_latency): CPUs stay out of idle "
     "states slower to wake than this, so real-time loops wake on time; -1 = no request"},
    // [boom]
    {WS_KEY(boom, nozzles), 4, 1, 32, "",
     "number of nozzles (solenoid valves) along the boom"},
    {WS_KEY(boom, nozzle_width_m), 0.5, 0.05, 3, "m",
     "ground width sprayed by one nozzle (w in the spray-rate law)"},
    {WS_KEY(boom, valve_open_delay_s), 0.02, 0, 0.5, "s",
     "valve opening delay: commands are issued this much before the patch arrives"},
    {WS_KEY(boom, valve_close_delay_s), 0.02, 0, 0.5, "s",
     "valve closing delay"},
    // [vision]
    {WS_KEY(vision, index), std::string("default"), 0, 0, "",
     "vegetation index; \"default\" = the vision library's measured best (weedspray-lab "
     "vision-eval); mono for GREY cameras",
     {"default", "exg_norm", "exg_raw", "exg_exr", "cive", "max_value", "weighted", "mono",
      "exg_chroma"}},
    {WS_KEY(vision, threshold), std::string("default"), 0, 0, "",
     "automatic threshold method, or fixed; \"default\" = the vision library's choice",
     {"default", "fit", "otsu", "kmeans", "hbt", "pso", "ipso", "fixed"}},
    {WS_KEY(vision, fixed_threshold), -1, -1, 255, "level",
     "level on the 8-bit index scale for threshold = \"fixed\", and for frames that are not "
     "bimodal where the index keeps a fixed level (full canopy; normalised ExG, ExG-ExR); -1 = "
     "the library's level for the index"},
    {WS_KEY(vision, grid_rows), 1, 1, 4, "",
     "zone rows along travel per frame (columns = the camera's nozzles)"},
    {WS_KEY(vision, weed_source), std::string("vegetation"), 0, 0, "",
     "what counts as weed. vegetation: every green pixel (bare soil: fallow, pre-plant); "
     "inter_row: vegetation between the crop rows, rows found as peaks of the column histogram "
     "and tracked from frame to frame (row crops; see row_band_cm); dnn: the weed class of the "
     "segmentation network in model; hybrid: colour vegetation minus the network's crop class "
     "grown by crop_margin_cm; plants: colour vegetation at the camera's resolution, each "
     "connected plant crop or weed by the network's votes (plants the network cannot resolve "
     "are weed; see min_plant_cm2). The rate law uses each zone's weed density",
     {"vegetation", "inter_row", "dnn", "hybrid", "plants"}},
    {WS_KEY(vision, row_band_cm), 30.0, 1, 500, "cm",
     "inter_row: width on the ground of the band around each crop row that counts as crop "
     "(converted to pixels with the camera's ground scale, camera.ground_mm_per_px or its "
     "mount geometry)"},
    {WS_KEY(vision, crop_margin_cm), 2.0, 0, 50, "cm",
     "hybrid: the network's crop mask is grown by this much on the ground before it is removed "
     "from the vegetation (converted to pixels with the camera's ground scale, "
     "camera.ground_mm_per_px or its mount geometry)"},
    {WS_KEY(vision, min_plant_cm2), 0.25, 0.01, 100, "cm2",
     "plants: connected vegetation smaller than this on the ground is a colour speck, not a "
     "plant (sprays nothing); also the least area the network must call weed inside a plant it "
     "calls crop for that part to stay weed (converted with the camera's ground scale)"},
    {WS_KEY(vision, model), std::string("weed-peanut-4mm.onnx"), 0, 0, "path",
     "dnn, hybrid, plants: the segmentation network, an ONNX file OpenCV DNN loads (checked with one "
     "forward pass at load), with its spec in NAME.json beside it (input size, normalisation, "
     "channel order, classes, the ground scale it learnt at, training data and licence; "
     "tools/train/train.py writes it). A relative path is looked up beside the configuration "
     "file that sets it, then among the installed models (/usr/share/weedspray/models from the "
     "package; a build tree also looks in its checkout's models/). The default is the shipped "
     "crop/weed/soil model trained on peanut fields at 4 mm per network pixel, which keeps up "
     "with a camera that sees about 1 mm per pixel (weed-peanut.onnx, also shipped, learnt at "
     "0.94 mm per network pixel: for cameras closer to the ground); train one for your crop with "
     "tools/train/train.py (docs/vision.md). The model_* and *_class keys below are optional: "
     "left unset they are the model's own; set, they must agree with its JSON"},
    {WS_KEY(vision, model_input_width), 320, 32, 4096, "px",
     "dnn, hybrid: override of the network input width (a multiple of the model's stride): the "
     "whole region is squeezed to it whatever the ground scale; unset = the region resampled to "
     "the model's ground scale (camera ground_mm_per_px)"},
    {WS_KEY(vision, model_input_height), 256, 32, 4096, "px",
     "dnn, hybrid: override of the network input height (see model_input_width)"},
    {WS_KEY(vision, model_mean), std::vector<double>{123.675, 116.28, 103.53}, 0, 255, "",
     "dnn, hybrid: per-channel mean subtracted from the 0..255 R, G, B values (3 numbers); "
     "must agree with the model's JSON"},
    {WS_KEY(vision, model_scale), 1.0 / 58.0, 1e-6, 1000, "",
     "dnn, hybrid: network input = (value - mean) x this; must agree with the model's JSON"},
    {WS_KEY(vision, model_rgb), true, 0, 1, "",
     "dnn, hybrid: the network takes R, G, B channel order (false: B, G, R); must agree with the "
     "model's JSON"},
    {WS_KEY(vision, model_classes), std::vector<std::string>{"soil", "crop", "weed"}, 0, 0, "",
     "dnn, hybrid: the network's output classes in channel order; must agree with the model's "
     "JSON"},
    {WS_KEY(vision, soil_class), 0, 0, 255, "",
     "dnn, hybrid: index in model_classes of soil (classes other than crop and weed count as "
     "soil); must agree with the model's JSON"},
    {WS_KEY(vision, crop_class), 1, 0, 255, "",
     "dnn, hybrid: index in model_classes of the crop; must agree with the model's JSON"},
    {WS_KEY(vision, weed_class), 2, 0, 255, "",
     "dnn, hybrid: index in model_classes of weeds; must agree with the model's JSON"},
    {WS_KEY(vision, max_network_pixels), 1500000, 1024, 16777216, "px",
     "dnn, hybrid: the largest network input (width x height) a camera's region may need at the "
     "model's ground scale; a camera that needs more is refused at load (inference time grows "
     "with it: weedspray-lab bench-vision)"},
    // [spray]
    {WS_KEY(spray, target_rate_l_per_ha), 0.0, 0, 5000, "L/ha",
     "the dose where the weeds cover a zone at max_density, in litres per hectare: sets "
     "nominal_flow_l_per_min = rate x 60 x boom.nozzle_width_m x nominal_speed_m_per_s / 10000 "
     "(set one of the two); 0 = the dose comes from nominal_flow_l_per_min"},
    {WS_KEY(spray, nominal_flow_l_per_min), 0.615, 0.01, 20, "L/min",
     "q_nom: nozzle flow that gives the nominal dose at the nominal speed (the dose in L/ha is "
     "10000 q_nom / (60 w v_nom): 205 L/ha at the defaults)"},
    {WS_KEY(spray, nominal_speed_m_per_s), 1.0, 0.1, 10, "m/s",
     "v_nom: speed of the nominal dose u = q_nom / (60 w v_nom)"},
    {WS_KEY(spray, max_density), 1.0, 0.01, 1, "",
     "k: the largest expected weed density (normaliser)"},
    {WS_KEY(spray, calibration_slope_l_per_min_per_pct),
     0.00393, 0.0001, 1, "L/min per %", "A in the calibrated valve line q = A s + b"},
    {WS_KEY(spray, calibration_offset_l_per_min), 0.217, -5, 5,
     "L/min", "b in the calibrated valve line q = A s + b"},
    {WS_KEY(spray, calibration_pressure_mpa), 0.4, 0.05, 1, "MPa",
     "pressure at which the valve line was calibrated (sqrt(P_cal/P) compensation)"},
    {WS_KEY(spray, duty_min_pct), 20.0, 0, 100, "%",
     "below this duty the valve stays closed"},
    {WS_KEY(spray, duty_max_pct), 80.0, 0, 100, "%",
     "above this duty the valve is held fully open"},
    {WS_KEY(spray, quantiser_levels), 7, 0, 14, "",
     "duty levels from duty_min_pct to duty_max_pct (plus closed and open); 0 = off, else 2..14"},
    {WS_KEY(spray, hysteresis_pct), 2.0, 0, 20, "%",
     "a quantised duty changes level only past this margin"},
    {WS_KEY(spray, decision_threshold), 0.001, 0, 1, "",
     "zones with a weed density below this are not sprayed; 0.001 (0.1 % of the zone) sits well "
     "below the 0.5 % that makes a zone weedy because detectors miss part of each small weed "
     "(weedspray-lab vision-eval --classes --sweep shows the trade-off)"},
    {WS_KEY(spray, low_duty_policy), std::string("raise_to_min"), 0, 0, "",
     "a weedy zone whose duty falls below duty_min_pct: raise_to_min sprays it at duty_min_pct "
     "(every weed sprayed); close leaves it dry (the wheat paper's s < 20 % -> 0 clamp)",
     {"raise_to_min", "close"}},
    {WS_KEY(spray, pressure_compensation), true, 0, 1, "",
     "scale duty by sqrt(P_cal / P) when the line pressure is off its calibration point"},
    // [pwm]
    {WS_KEY(pwm, frequency_hz), 5.0, 1, 20, "Hz", "valve PWM frequency"},
    {WS_KEY(pwm, staggered), true, 0, 1, "",
     "offset the valves' periods by T/N so they do not switch together"},
    {WS_KEY(pwm, order), std::string("outer_first"), 0, 0, "",
     "order of the staggered phases along the boom",
     {"outer_first", "inner_first", "left_to_right"}},
    {WS_KEY(pwm, min_on_s), 0.01, 0, 0.5, "s", "shortest valve opening"},
    {WS_KEY(pwm, min_off_s), 0.01, 0, 0.5, "s", "shortest valve closing"},
    {WS_KEY(pwm, dead_man_s), 0.5, 0.05, 10, "s",
     "valves close if no fresh duty command arrived for this long"},
    // [pressure]
    {WS_KEY(pressure, setpoint_mpa), 0.4, 0.05, 1.0, "MPa",
     "line pressure set-point (changeable over D-Bus)"},
    {WS_KEY(pressure, controller), std::string("fuzzy_pid"), 0, 0, "",
     "pressure controller (fuzzy_pid won the fair tuning, README control figures; with pid set "
     "kp = 39.31, ki = 392.4, kd = 0.9222)",
     {"fuzzy_pid", "pid"}},
    {WS_KEY(pressure, loop_hz), 100.0, 10, 1000, "Hz", "pressure loop rate"},
    {WS_KEY(pressure, kp), 33.38, 0, 10000, "1/MPa",
     "base proportional gain Kp' (controller output: return-valve closure 0..1)"},
    {WS_KEY(pressure, ki), 352.3, 0, 100000, "1/(MPa s)", "base integral gain Ki'"},
    {WS_KEY(pressure, kd), 1.009, 0, 1000, "s/MPa", "base derivative gain Kd'"},
    {WS_KEY(pressure, cp), 0.7823, 0, 1000, "1/MPa", "fuzzy correction weight Cp (fuzzy_pid only)"},
    {WS_KEY(pressure, ci), 45.96, 0, 10000, "1/(MPa s)",
     "fuzzy correction weight Ci (fuzzy_pid only)"},
    {WS_KEY(pressure, cd), 0.0, 0, 1000, "s/MPa",
     "fuzzy correction weight Cd (fuzzy_pid only)"},
    {WS_KEY(pressure, range_mpa), 0.2, 0.01, 10, "MPa",
     "Vmax - Vmin used to quantise the error for the fuzzy rules"},
    {WS_KEY(pressure, sensor_min_mpa), 0.0, 0, 10, "MPa",
     "pressure read at 4 mA"},
    {WS_KEY(pressure, sensor_max_mpa), 1.0, 0.1, 10, "MPa",
     "pressure read at 20 mA"},
    {WS_KEY(pressure, output_min), 0.0, 0, 1, "",
     "lowest return-valve closure (0 = fully open)"},
    {WS_KEY(pressure, output_max), 1.0, 0, 1, "",
     "highest return-valve closure (1 = fully closed)"},
    // [gpio]
    {WS_KEY(gpio, chip), std::string("gpiochip0"), 0, 0, "",
     "GPIO chip (name or /dev path) holding every line below"},
    {WS_KEY(gpio, valve_offsets), std::vector<int>{}, 0, 1023, "line",
     "valve line offsets, one per nozzle in boom order (empty = not wired)"},
    {WS_KEY(gpio, valve_names), std::vector<std::string>{}, 0, 0, "",
     "valve line names instead of offsets, one per nozzle (as in gpioinfo; empty = use offsets)"},
    {WS_KEY(gpio, valve_active_low), false, 0, 1, "",
     "valve lines are active-low"},
    {WS_KEY(gpio, pump_offset), -1, -1, 1023, "line",
     "pump relay line (-1 = not wired)"},
    {WS_KEY(gpio, pump_name), std::string(""), 0, 0, "",
     "pump relay line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, pump_active_low), false, 0, 1, "",
     "pump relay line is active-low"},
    {WS_KEY(gpio, buzzer_offset), -1, -1, 1023, "line",
     "alarm buzzer line (-1 = none)"},
    {WS_KEY(gpio, buzzer_name), std::string(""), 0, 0, "",
     "alarm buzzer line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, led_offset), -1, -1, 1023, "line", "alarm LED line (-1 = none)"},
    {WS_KEY(gpio, led_name), std::string(""), 0, 0, "",
     "alarm LED line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, heartbeat_offset), -1, -1, 1023, "line",
     "heartbeat output (-1 = none): a square wave from the valve thread while the real-time "
     "core runs, low when it stops, while a Fault is latched and after a refused valve or pump "
     "write; drives a retriggerable relay that powers the valves (and the pump)"},
    {WS_KEY(gpio, heartbeat_name), std::string(""), 0, 0, "",
     "heartbeat line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, heartbeat_hz), 50.0, 1, 250, "Hz",
     "heartbeat square-wave frequency (the relay's hold-up time must exceed a few periods)"},
    {WS_KEY(gpio, heartbeat_opt_out), false, 0, 1, "",
     "hardware mode starts only with a heartbeat output (heartbeat_offset or heartbeat_name), "
     "the channel that cuts valves and pump when the daemon stops driving them; true starts "
     "without one, with a warning at every start"},
    {WS_KEY(gpio, key_offset), -1, -1, 1023, "line",
     "start/stop key input (-1 = none); each press toggles Idle/Spraying"},
    {WS_KEY(gpio, key_name), std::string(""), 0, 0, "",
     "start/stop key line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, key_active_low), true, 0, 1, "",
     "start/stop key pulls the line low when pressed"},
    {WS_KEY(gpio, estop_offset), -1, -1, 1023, "line",
     "emergency-stop input (-1 = none): a normally closed circuit; when it opens (a pressed "
     "button, a cut wire) valves close and the pump stops within milliseconds, latched until "
     "the circuit is closed again and the alarms are cleared"},
    {WS_KEY(gpio, estop_name), std::string(""), 0, 0, "",
     "emergency-stop line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, estop_active_low), true, 0, 1, "",
     "the closed E-stop circuit pulls the line low (contact to ground, pull-up resistor): an "
     "open circuit reads high"},
    {WS_KEY(gpio, estop_opt_out), false, 0, 1, "",
     "hardware mode starts only with an emergency-stop input (estop_offset or estop_name); "
     "true starts without one, with a warning at every start"},
    {WS_KEY(gpio, flow_offset), -1, -1, 1023, "line",
     "flow meter pulse input (-1 = none)"},
    {WS_KEY(gpio, flow_name), std::string(""), 0, 0, "",
     "flow meter line by name instead of offset (empty = use the offset)"},
    {WS_KEY(gpio, wheel_offset), -1, -1, 1023, "line",
     "Hall wheel sensor pulse input (-1 = none)"},
    {WS_KEY(gpio, wheel_name), std::string(""), 0, 0, "",
     "Hall wheel sensor line by name instead of offset (empty = use the offset)"},
    // [adc]
    {WS_KEY(adc, source), std::string("iio"), 0, 0, "",
     "the pressure ADC: a Linux IIO device, or a Modbus RTU analog input module on the "
     "[analog_modbus] bus", {"iio", "modbus"}},
    {WS_KEY(adc, iio_device), std::string("iio:device0"), 0, 0, "",
     "IIO device reading the pressure sensor: iio:deviceN, its path, or its name (ads1015)"},
    {WS_KEY(adc, pressure_channel), 0, 0, 63, "",
     "IIO input channel N (in_voltageN_raw) of the pressure sensor"},
    {WS_KEY(adc, iio_scale_mv), 0.0, 0, 1e6, "mV/count",
     "IIO millivolts per count, for a driver without in_voltageN_scale or in_voltage_scale "
     "(0 = read the driver's scale)"},
    {WS_KEY(adc, shunt_ohms), 165.0, 1, 10000, "ohm",
     "I/V resistor of the 4-20 mA loop (165 ohm maps 20 mA to 3.3 V)"},
    {WS_KEY(adc, modbus_slave_id), 2, 1, 247, "",
     "source = \"modbus\": the input module's slave address"},
    {WS_KEY(adc, modbus_register), 0, 0, 65535, "",
     "source = \"modbus\": the register holding the sensor voltage"},
    {WS_KEY(adc, modbus_register_type), std::string("input"), 0, 0, "",
     "source = \"modbus\": read it as an input register (function 04) or a holding register "
     "(03)", {"input", "holding"}},
    {WS_KEY(adc, modbus_volts_per_count), 0.001, 1e-9, 1, "V/count",
     "source = \"modbus\": volts = register value x this (the module's unit, e.g. mV)"},
    // [dac]
    {WS_KEY(dac, source), std::string("iio"), 0, 0, "",
     "the return-valve DAC: a Linux IIO device, or a Modbus RTU analog output module on the "
     "[analog_modbus] bus", {"iio", "modbus"}},
    {WS_KEY(dac, iio_device), std::string("iio:device1"), 0, 0, "",
     "IIO device driving the proportional return valve"},
    {WS_KEY(dac, channel), 0, 0, 63, "", "IIO output channel N (out_voltageN_raw)"},
    {WS_KEY(dac, iio_scale_mv), 0.0, 0, 1e6, "mV/count",
     "IIO millivolts per count, for a driver without out_voltageN_scale or out_voltage_scale "
     "(0 = read the driver's scale)"},
    {WS_KEY(dac, full_scale_v), 3.3, 0.5, 12, "V",
     "DAC voltage for a 100 % valve command"},
    {WS_KEY(dac, return_valve_open_at), std::string("full_scale"), 0, 0, "",
     "the DAC output that opens the return valve fully, its safe position (no pressure held): "
     "full_scale for a valve that opens with its control voltage (then a DAC reset, a "
     "brown-out or a broken wire closes it: wire a fail-open bypass, docs/hardware.md), zero "
     "for a reverse-acting valve that opens at 0 V, so a dead DAC opens the relief path",
     {"full_scale", "zero"}},
    {WS_KEY(dac, modbus_slave_id), 3, 1, 247, "",
     "source = \"modbus\": the output module's slave address"},
    {WS_KEY(dac, modbus_register), 0, 0, 65535, "",
     "source = \"modbus\": the holding register written with the valve voltage (function 06)"},
    {WS_KEY(dac, modbus_volts_per_count), 0.001, 1e-9, 1, "V/count",
     "source = \"modbus\": register value = volts / this"},
    {WS_KEY(dac, modbus_comm_timeout_register), -1, -1, 65535, "",
     "source = \"modbus\": the module's communication-timeout holding register (its manual: "
     "\"watchdog\", \"communication loss\" or \"host timeout\"), so that the module itself "
     "sets its output safe when the daemon stops writing (a crash, a freeze, a cut RS-485 "
     "pair); the daemon then rewrites an unchanged value every third of the timeout. -1: "
     "the module has none"},
    {WS_KEY(dac, modbus_comm_timeout_s), 0.5, 0.05, 60, "s",
     "source = \"modbus\": the communication timeout written there"},
    {WS_KEY(dac, modbus_comm_timeout_counts_per_s), 1000.0, 0.001, 1e6, "counts/s",
     "source = \"modbus\": the timeout register's unit, as counts per second (1000: "
     "milliseconds, 10: tenths of a second, 1: seconds)"},
    {WS_KEY(dac, modbus_safe_value_register), -1, -1, 65535, "",
     "source = \"modbus\": the holding register of the value the module puts out on a "
     "communication loss (and, on many modules, at power-up); written with the return valve's "
     "safe value at start. -1: the module has none"},
    {WS_KEY(dac, write_failures_tolerated), 2, 0, 20, "",
     "failed DAC writes in a row that are only counted and logged, not a fault: each is "
     "superseded by the next pressure-loop period's write and the valve holds its last value "
     "meanwhile (2, like a pressure sample that goes stale after 3 periods); the next failure "
     "raises output_write_failed, and a failed safe write always does"},
    // [analog_modbus]
    {WS_KEY(analog_modbus, device), std::string("/dev/ttyUSB1"), 0, 0, "path",
     "RS-485 serial device of the Modbus analog modules; not the tank sensor's [modbus] port, "
     "which another thread polls"},
    {WS_KEY(analog_modbus, baud), 115200, 1200, 921600, "baud",
     "serial speed: a one-register transaction is about 22 character times, 2.1 ms at 115200 "
     "and 25 ms at 9600; it must fit in half a pressure-loop period"},
    {WS_KEY(analog_modbus, parity), std::string("N"), 0, 0, "", "serial parity",
     {"N", "E", "O"}},
    {WS_KEY(analog_modbus, timeout_s), 0.02, 0.005, 1, "s",
     "response timeout; a module silent for 3 pressure-loop periods makes the sensor stale "
     "(pump off, valves closed)"},
    // [flow]
    {WS_KEY(flow, pulses_per_litre), 8500.0, 1, 1e6, "pulses/L",
     "flow meter constant"},
    {WS_KEY(flow, counter), std::string(""), 0, 0, "",
     "count the flow meter in the kernel (Linux Counter subsystem, e.g. interrupt-cnt bound to "
     "the meter's GPIO in the device tree) instead of GPIO edge events: counterN, its path, or "
     "its name. For meters pulsing faster than ~10 kHz, where edge events can be lost. Empty = "
     "gpio.flow_offset / gpio.flow_name"},
    // [calibration]
    {WS_KEY(calibration, duties_pct), std::vector<double>{20.0, 40.0, 60.0, 80.0}, 1, 99, "%",
     "sprayctl calibrate nozzles: each nozzle alone at each of these duties (at least 2 "
     "different; the line q = A s + b is fitted between the lowest and the highest)"},
    {WS_KEY(calibration, settle_s), 2.0, 0, 60, "s",
     "time skipped at each point of the sweep while valve, pressure and meter settle"},
    {WS_KEY(calibration, measure_s), 5.0, 0.2, 600, "s",
     "time the meter is counted at each point (the pulses per point: measure_s x K x flow; "
     "5 s of one nozzle at 20 % gives ~200 pulses at 8500 pulses/L)"},
    {WS_KEY(calibration, min_r_squared), 0.98, 0, 1, "",
     "a nozzle whose fitted line has R^2 below this keeps the [spray] line (a sticking valve, a "
     "meter too coarse for one nozzle)"},
    {WS_KEY(calibration, meter_max_change_pct), 25.0, 1, 100, "%",
     "sprayctl calibrate meter --volume: a result further than this from flow.pulses_per_litre "
     "is refused as a likely typo in the volume (the catch test still awaits the right one); "
     "a meter that truly differs that much needs flow.pulses_per_litre set"},
    {WS_KEY(calibration, full_open), true, 0, 1, "",
     "sprayctl calibrate nozzles: also meter each nozzle held open (100 %, one point more): a "
     "request at or above that flow holds the valve open, and the flow trim and "
     "calibration_drift then judge windows with held-open nozzles too (without it they wait "
     "for windows without any)"},
    // [nozzle_health]
    {WS_KEY(nozzle_health, enabled), false, 0, 1, "",
     "judge each nozzle's flow from the line meter while spraying (staggered PWM phases make "
     "the nozzles separable) and raise nozzle_flow_fault naming a blocked or over-flowing one"},
    {WS_KEY(nozzle_health, baseline_s), 60.0, 1, 3600, "s",
     "spraying time over which each nozzle's flow is learned as its baseline"},
    {WS_KEY(nozzle_health, time_constant_s), 6.0, 0.5, 600, "s",
     "forgetting time of the running per-nozzle estimate (the ratios shown; band: judged)"},
    {WS_KEY(nozzle_health, judge), std::string("band"), 0, 0, "",
     "band: a nozzle whose ratio is off 1 by alarm_fraction for alarm_hold_s is a fault; cusum: "
     "the evidence that one nozzle's flow changed by alarm_fraction, summed over the meter's "
     "windows (the lab's 20 % blockage named in 3.5 s instead of 7-9 s, no false alarm in 400 "
     "machine-minutes; but the daemon's simulator still gets a false alarm within 240 s of "
     "healthy spraying: the valves' unequal opening and closing delays make the flow per "
     "commanded second depend on the duty, and windows at duties far from the first 60 s are "
     "not judged: README, experiment blockage)",
     {"band", "cusum"}},
    {WS_KEY(nozzle_health, alarm_fraction), 0.12, 0.01, 0.99, "",
     "band: a nozzle whose flow / baseline is off 1 by more than this is a fault...; cusum: the "
     "change of one nozzle's flow, as a fraction of its baseline, looked for..."},
    {WS_KEY(nozzle_health, alarm_hold_s), 1.0, 0, 600, "s", "band: ...once it lasted this long"},
    {WS_KEY(nozzle_health, alarm_threshold), 24.0, 1, 1000, "",
     "cusum: ...named once its evidence (log-likelihood ratio) exceeds this: higher, fewer false "
     "alarms and later names (24: about 1 false alarm in 10^5 machine-minutes on the lab's "
     "fleet)"},
    // [wheel]
    {WS_KEY(wheel, source), std::string("pulses"), 0, 0, "",
     "speed from the Hall wheel sensor, or a fixed speed", {"pulses", "fixed"}},
    {WS_KEY(wheel, pulses_per_metre), 100.0, 0.1, 1e5, "pulses/m",
     "wheel sensor constant"},
    {WS_KEY(wheel, fixed_speed_m_per_s), 1.0, 0, 10, "m/s",
     "speed assumed when source = \"fixed\""},
    // [speed]
    {WS_KEY(speed, source), std::string("wheel"), 0, 0, "",
     "the ground speed of the rate law: \"wheel\" as [wheel] says (its pulses, or its fixed "
     "speed), \"gnss\" the receiver's speed over ground ([gnss] enabled; the wheel's pulses stay "
     "the distance base when wheel.source = \"pulses\"; without a usable fix the speed falls back "
     "to the wheel's pulses, else wheel.fixed_speed_m_per_s), \"fixed\" wheel.fixed_speed_m_per_s, "
     "\"fleet\" another board's speed and distance over the broker (fleet.speed_from; both the "
     "speed and the distance base, the wheel unused)",
     {"wheel", "fixed", "gnss", "fleet"}},
    {WS_KEY(speed, shared_timeout_s), 0.5, 0.1, 2.0, "s",
     "speed.source = \"fleet\": no sample from the owning board for this long closes every "
     "valve and raises shared_speed_lost (at 2.5 m/s, 0.5 s is 1.25 m travelled on an old "
     "speed)"},
    // [gnss]
    {WS_KEY(gnss, enabled), false, 0, 1, "",
     "read position, speed and course from gpsd (the receiver is gpsd's: NMEA, u-blox, RTK)"},
    {WS_KEY(gnss, host), std::string("localhost"), 0, 0, "", "gpsd's host"},
    {WS_KEY(gnss, port), 2947, 1, 65535, "", "gpsd's TCP port"},
    {WS_KEY(gnss, lost_fix_timeout_s), 2.0, 0.2, 60, "s",
     "no 2D/3D fix for this long raises gnss_fix_lost (and a receiver reporting no fix makes "
     "speed.source = \"gnss\" fall back at once)"},
    {WS_KEY(gnss, first_fix_timeout_s), 60.0, 1, 3600, "s",
     "after start, no usable fix for this long raises gnss_fix_lost (a receiver's cold start "
     "takes 30-60 s); afterwards lost_fix_timeout_s applies"},
    {WS_KEY(gnss, reconnect_max_s), 5.0, 0.1, 600, "s",
     "while gpsd is away, reconnection attempts back off from 0.25 s up to this"},
    {WS_KEY(gnss, antenna_ahead_of_nozzles_m), 0.0, -50, 50, "m",
     "the antenna's distance ahead of the nozzle line along the direction of travel (negative: "
     "behind it); maps place each nozzle's patch from the antenna's position and course"},
    {WS_KEY(gnss, antenna_right_of_centre_m), 0.0, -50, 50, "m",
     "the antenna's distance right of the boom's centre, looking forward (negative: left)"},
    // [turn]
    {WS_KEY(turn, compensation), true, 0, 1, "",
     "on a curve give each nozzle the rate and schedule of its own ground speed, v + yaw rate x "
     "its lateral offset (nozzle 0 is the leftmost, looking forward); needs a yaw source"},
    {WS_KEY(turn, yaw_source), std::string("gnss"), 0, 0, "",
     "where the yaw rate comes from: \"gnss\" the rate of change of the receiver's course "
     "([gnss] enabled), \"imu\" a gyro through IIO (turn.imu_device), \"none\" "
     "no turn compensation",
     {"gnss", "none", "imu"}},
    {WS_KEY(turn, imu_device), std::string(""), 0, 0, "",
     "yaw_source = \"imu\": the IIO gyro (e.g. MPU-6050 with inv_mpu6050, LSM6DS3 with "
     "st_lsm6dsx): \"iio:deviceN\", its directory, or its name; read at 100 Hz from "
     "in_anglvel_<axis>_raw x its scale"},
    {WS_KEY(turn, imu_axis), std::string("z"), 0, 0, "",
     "the gyro axis that is vertical on the machine", {"x", "y", "z"}},
    {WS_KEY(turn, imu_axis_up), true, 0, 1, "",
     "that axis points up (IIO's right-hand rule: a left turn is positive about an up axis); "
     "false when the sensor is mounted with it pointing down"},
    {WS_KEY(turn, min_speed_m_per_s), 0.3, 0, 5, "m/s",
     "below this ground speed the course over ground is noise: the yaw rate is taken as 0"},
    {WS_KEY(turn, yaw_filter_s), 0.5, 0, 10, "s",
     "time constant of the yaw rate's low-pass filter (0 = none)"},
    // [modbus]
    {WS_KEY(modbus, enabled), false, 0, 1, "",
     "read the tank level from a Modbus RTU sensor"},
    {WS_KEY(modbus, device), std::string("/dev/ttyUSB0"), 0, 0, "path",
     "RS-485 serial device"},
    {WS_KEY(modbus, baud), 9600, 1200, 921600, "baud", "serial speed"},
    {WS_KEY(modbus, parity), std::string("N"), 0, 0, "", "serial parity",
     {"N", "E", "O"}},
    {WS_KEY(modbus, slave_id), 1, 1, 247, "", "Modbus slave address"},
    {WS_KEY(modbus, tank_register), 0, 0, 65535, "",
     "holding register with the tank level"},
    {WS_KEY(modbus, tank_scale_pct_per_count), 0.1, 1e-6, 100,
     "% per count", "tank level = register value x this"},
    {WS_KEY(modbus, poll_period_s), 1.0, 0.05, 60, "s", "polling period"},
    {WS_KEY(modbus, timeout_s), 0.5, 0.01, 10, "s", "response timeout"},
    // [alarms]
    {WS_KEY(alarms, over_pressure_mpa), 0.9, 0.1, 10, "MPa",
     "over-pressure: pump off and Fault; must lie below pressure.sensor_max_mpa (a sensor that "
     "saturates at its full scale never reads above it)"},
    {WS_KEY(alarms, sensor_fault_low_ma), 3.6, 3.0, 3.8, "mA",
     "a loop current below this is a broken sensor wire or an unpowered sensor (NAMUR NE 43: "
     "3.6 and below is a failure, 3.8 the bottom of the measuring range); the range keeps a cut "
     "wire (0-1 mA) a fault"},
    {WS_KEY(alarms, sensor_fault_high_ma), 21.0, 20.5, 22, "mA",
     "a loop current above this is a shorted sensor (NAMUR NE 43: 21 and above is a failure, "
     "20.5 the top of the measuring range)"},
    {WS_KEY(alarms, blocked_pressure_mpa), 0.7, 0.05, 10, "MPa",
     "line blocked: pressure above this while spraying ..."},
    {WS_KEY(alarms, blocked_flow_l_per_min), 0.05, 0, 100, "L/min",
     "... and flow below this"},
    {WS_KEY(alarms, no_flow_l_per_min), 0.02, 0, 100, "L/min",
     "no flow: valves open but flow below this"},
    {WS_KEY(alarms, tank_low_pct), 15.0, 0, 100, "%", "tank low warning"},
    {WS_KEY(alarms, tank_empty_pct), 3.0, 0, 100, "%",
     "tank empty: spraying stops"},
    {WS_KEY(alarms, modbus_silent_s), 5.0, 0.1, 600, "s",
     "no Modbus answer for this long raises modbus_silent"},
    {WS_KEY(alarms, camera_stall_s), 1.0, 0.05, 60, "s",
     "no frame for this long raises camera_lost"},
    {WS_KEY(alarms, debounce_s), 1.0, 0, 60, "s",
     "a flow/pressure condition must hold this long before it raises an alarm"},
    {WS_KEY(alarms, sensor_fault_hold_s), 0.15, 0, 5, "s",
     "a pressure-sensor fault must last this long before it latches Fault (the pump is off "
     "from the first bad reading)"},
    {WS_KEY(alarms, timing_tolerance_ms), 5.0, 0.5, 100, "ms",
     "while spraying, a valve edge or control-loop cycle later than this, or a missed "
     "pressure-loop period, is a deadline miss that affects spraying"},
    {WS_KEY(alarms, control_overrun_limit), 3, 1, 1000000, "",
     "deadline misses that affect spraying (see timing_tolerance_ms) within one second that "
     "raise control_overruns"},
    {WS_KEY(alarms, calibration_drift_pct), 5.0, 0.5, 50, "%",
     "the line meter's flow and what the calibrated nozzles promise at the commanded duties "
     "(a minute's average of spraying) further apart than this (meter drift, worn nozzles) ..."},
    {WS_KEY(alarms, calibration_drift_hold_s), 30.0, 1, 3600, "s",
     "... for this long raises calibration_drift, a warning: run sprayctl calibrate meter, then "
     "calibrate nozzles"},
    {WS_KEY(alarms, closed_flow_l_per_min), 0.1, 0.02, 2, "L/min",
     "the line meter's flow above this while every valve has been commanded closed for "
     "closed_flow_settle_s (then for debounce_s) raises flow_with_valves_closed, a Fault: a "
     "leaking or stuck-open valve, or a valve wire that no longer closes it"},
    {WS_KEY(alarms, closed_flow_settle_s), 2.0, 1, 30, "s",
     "after the last valve closes, the line drains and the meter's window empties for this long "
     "before flow_with_valves_closed is judged"},
    // [log]
    {WS_KEY(log, dir), std::string(""), 0, 0, "path",
     "as-applied CSV folder (empty = <daemon.state_dir>/as-applied)"},
    {WS_KEY(log, rotate_bytes), 10 * 1024 * 1024, 4096, INT_MAX, "bytes",
     "start a new as-applied file past this size"},
    {WS_KEY(log, keep_files), 150, 1, 10000, "",
     "rotated as-applied files kept (oldest deleted); the default 150 x 10 MB holds about 6 days "
     "of 8 h with 24 nozzles (1.35 kB a record, 5 records a second), so a week's work can be "
     "exported before it goes"},
    {WS_KEY(log, min_free_mb), 64, 0, 1000000, "MB",
     "free space in the as-applied folder's file system under this raises records_disk_full, a "
     "warning that clears itself: spraying goes on; export and delete old files (the default "
     "64 MB holds about 2.5 h of 24 nozzles); 0 = only a failing write raises it. While writes "
     "fail, lines wait in memory (about 10 min of 24 nozzles) and are written once space "
     "returns; beyond that they are dropped and counted (the seq column shows the gap)"},
    // [sim]
    {WS_KEY(sim, speed_profile), std::string("sine"), 0, 0, "",
     "simulated travel speed over time", {"constant", "sine", "ramp"}},
    {WS_KEY(sim, speed_min_m_per_s), 0.5, 0, 10, "m/s",
     "lowest simulated speed (constant uses the maximum)"},
    {WS_KEY(sim, speed_max_m_per_s), 2.5, 0.01, 10, "m/s",
     "highest simulated speed"},
    {WS_KEY(sim, speed_period_s), 20.0, 0.1, 3600, "s",
     "period of the sine/ramp speed profile"},
    {WS_KEY(sim, images_dir), std::string(""), 0, 0, "path",
     "field images (PNG or JPEG files) used as the simulated camera (empty = the bundled ones)"},
    {WS_KEY(sim, images_mm_per_px), 0.0, 0, 100, "mm",
     "ground size of one pixel of images_dir's images: each simulated frame is then the ground "
     "as the [[camera]] sees it (its frame size and ground_mm_per_px), consecutive images "
     "resampled and laid edge to edge; 0 = each image is one frame as it is, of unknown ground "
     "scale (the weed model then takes it squeezed to the model's own input size)"},
    {WS_KEY(sim, seed), 1, 0, INT_MAX, "", "random seed of the simulation"},
    {WS_KEY(sim, wheel_slip_pct), 0.0, -20, 45, "%",
     "the simulated wheel sensor turns this much more than the ground it covers (a driven "
     "wheel spinning > 0, a trailed wheel skidding < 0): its pulses per ground metre are "
     "wheel.pulses_per_metre x (1 + slip), what sprayctl calibrate-wheel measures"},
    // [fleet]
    {WS_KEY(fleet, enabled), false, 0, 1, "",
     "weedspray-fleet joins this board to the machine over an MQTT broker: it publishes the "
     "daemon's state and forwards the broker's commands as D-Bus calls (docs/fleet.md); the "
     "daemon itself ignores [fleet]"},
    {WS_KEY(fleet, host), std::string("localhost"), 0, 0, "", "the MQTT broker's host"},
    {WS_KEY(fleet, port), 1883, 1, 65535, "",
     "the broker's TCP port (1883 plain, 8883 usually with TLS)"},
    {WS_KEY(fleet, machine), std::string("sprayer"), 0, 0, "",
     "the machine's name, shared by all its boards: topics weedspray/<machine>/<board>/...; "
     "letters, digits, '-' and '_'"},
    {WS_KEY(fleet, board), std::string("board1"), 0, 0, "",
     "this board's name on the machine, unique on it; letters, digits, '-' and '_'"},
    {WS_KEY(fleet, first_nozzle_offset_m), 0.0, -50, 50, "m",
     "this board's first nozzle along the boom: its distance from the boom's left end, looking "
     "forward (the cab draws the boards' nozzles in this order)"},
    {WS_KEY(fleet, keepalive_s), 5, 5, 300, "s",
     "MQTT keep-alive: the broker marks a board whose link went silent lost after 1.5 x this "
     "(a bridge that exits or is killed is marked lost at once)"},
    {WS_KEY(fleet, username), std::string(""), 0, 0, "",
     "the broker user name (empty = anonymous)"},
    {WS_KEY(fleet, password_file), std::string(""), 0, 0, "path",
     "a file whose first line is the broker password (empty = none); readable by the bridge's "
     "user only"},
    {WS_KEY(fleet, tls_cafile), std::string(""), 0, 0, "path",
     "TLS: the CA certificate that signed the broker's (empty = no TLS)"},
    {WS_KEY(fleet, tls_certfile), std::string(""), 0, 0, "path",
     "TLS: this board's client certificate, for brokers that require one (with tls_keyfile)"},
    {WS_KEY(fleet, tls_keyfile), std::string(""), 0, 0, "path",
     "TLS: the client certificate's private key"},
    {WS_KEY(fleet, commands), std::string("operator"), 0, 0, "",
     "the command kinds taken from the broker, as the D-Bus groups split them: none (publish "
     "only), operator (start, stop, set_pressure, clear_alarms), admin (also reload_config); "
     "any other is refused as unauthorised",
     {"none", "operator", "admin"}},
    {WS_KEY(fleet, on_board_lost), std::string("continue"), 0, 0, "",
     "when another board of the machine is lost (its bridge or daemon gone, the broker's last "
     "will), this board sprays on (continue) or stops (stop: the whole boom stops with any "
     "board)",
     {"continue", "stop"}},
    {WS_KEY(fleet, on_broker_lost), std::string("stop"), 0, 0, "",
     "when this board's connection to the broker is lost (so the cab can no longer stop it), it "
     "stops spraying (stop) or sprays on (continue); it reconnects by itself either way",
     {"stop", "continue"}},
    {WS_KEY(fleet, picture_interval_s), 5.0, 0, 3600, "s",
     "how often the bridge publishes camera 0's live-view picture (the daemon's Snapshot: a PNG "
     "with the weed overlay) on weedspray/<machine>/<board>/picture, retained, for the cab page; "
     "0 = never"},
    {WS_KEY(fleet, motion_rate_hz), 0.0, 0, 100, "Hz",
     "how often the bridge publishes this board's ground speed and distance with its daemon's "
     "time stamp on weedspray/<machine>/<board>/motion (QoS 0, not retained) for boards that "
     "take their speed from it; 0 = never (20 on the board that owns the speed)"},
    {WS_KEY(fleet, speed_from), std::string(""), 0, 0, "",
     "the board whose motion topic the bridge hands to this board's daemon (FeedSharedMotion), "
     "for speed.source = \"fleet\"; empty = none"},
    // [cab]
    {WS_KEY(cab, listen_address), std::string("127.0.0.1"), 0, 0, "",
     "weedspray-cab serves the cab page on this address: the cab's network address (or "
     "0.0.0.0) for a phone or tablet; whoever reaches it can start and stop the machine. It "
     "reads the boards from the broker and machine of [fleet]"},
    {WS_KEY(cab, port), 8080, 1, 65535, "", "the cab page's TCP port"},
  };
  // clang-format on
  return keys;
}

const std::vector<KeySpec<CameraSection>>& camera_keys() {
  // clang-format off
  static const std::vector<KeySpec<CameraSection>> keys = {
    {WS_CAM(device), std::string("/dev/video0"), 0, 0, "path", "V4L2 device"},
    {WS_CAM(width), 1280, 16, 8192, "px", "frame width"},
    {WS_CAM(height), 800, 16, 8192, "px", "frame height"},
    {WS_CAM(fps), 30.0, 0.1, 240, "Hz", "frame rate requested"},
    {WS_CAM(format), std::string("YUYV"), 0, 0, "", "pixel format",
     {"YUYV", "MJPG", "RGB3", "GREY"}},
    {WS_CAM(exposure_us), 0, 0, 1000000, "us", "fixed exposure (0 = automatic)"},
    {WS_CAM(white_balance_k), 0, 0, 15000, "K",
     "fixed white balance colour temperature, automatic white balance off: vegetation indices "
     "compare colours, so a fixed balance keeps thresholds steady (0 = leave the camera's own "
     "setting)"},
    {WS_CAM(mount_height_m), 1.0, 0.1, 10, "m", "lens height above ground"},
    {WS_CAM(tilt_deg), 30.0, 0, 80, "deg", "optical axis from vertical, looking forward"},
    {WS_CAM(vfov_deg), 40.0, 1, 170, "deg", "vertical (along travel) field of view"},
    {WS_CAM(ground_mm_per_px), 0.0, 0, 100, "mm",
     "ground size of one pixel at the image centre, across travel; 0 = from mount_height_m, "
     "tilt_deg and vfov_deg (square pixels). The weed model's input is resampled to the ground "
     "scale it learnt at"},
    {WS_CAM(distance_to_nozzles_m), 1.2, 0, 50, "m",
     "nozzle line behind the camera's nadir (ground point under the lens), along travel"},
    {WS_CAM(first_nozzle), 0, 0, 31, "", "first nozzle (0-based) this camera steers"},
    {WS_CAM(nozzle_count), 4, 1, 32, "", "number of consecutive nozzles this camera steers"},
  };
  // clang-format on
  return keys;
}

const KeySpec<Config>& config_key(std::string_view full_name) {
  const auto& keys = config_keys();
  const auto found = std::find_if(keys.begin(), keys.end(),
                                  [&](const auto& spec) { return spec.full_name() == full_name; });
  if (found == keys.end())
    throw std::out_of_range("no configuration key " + std::string(full_name));
  return *found;
}

std::string outside_key_range(std::string_view full_name, double value) {
  const auto& spec = config_key(full_name);
  if (value >= spec.min && value <= spec.max) return {};  // a NaN is outside
  std::ostringstream message;
  message << value << " outside " << full_name << "'s range " << spec.min << ".." << spec.max;
  if (!spec.unit.empty()) message << " " << spec.unit;
  return message.str();
}

bool overrides_model_spec(std::string_view full_name) {
  static constexpr std::array<std::string_view, 9> kKeys = {
      "vision.model_input_width", "vision.model_input_height", "vision.model_mean",
      "vision.model_scale",       "vision.model_rgb",          "vision.model_classes",
      "vision.soil_class",        "vision.crop_class",         "vision.weed_class"};
  return std::find(kKeys.begin(), kKeys.end(), full_name) != kKeys.end();
}

bool is_safety_limit(std::string_view full_name) {
  static constexpr std::array<std::string_view, 12> kKeys = {
      "alarms.over_pressure_mpa",     "alarms.sensor_fault_low_ma",
      "alarms.sensor_fault_high_ma",  "alarms.sensor_fault_hold_s",
      "alarms.blocked_pressure_mpa",  "alarms.blocked_flow_l_per_min",
      "alarms.no_flow_l_per_min",     "alarms.debounce_s",
      "alarms.tank_empty_pct",        "alarms.camera_stall_s",
      "alarms.closed_flow_l_per_min", "alarms.closed_flow_settle_s"};
  return std::find(kKeys.begin(), kKeys.end(), full_name) != kKeys.end();
}

}  // namespace weedspray::daemon
