// SPDX-License-Identifier: Apache-2.0
// The configuration keys of [daemon], [boom], [vision], [spray], [pwm], [pressure]: what the
// sprayer does and how fast.
#include <climits>

#include "daemon/config/config_key_tables.hpp"

// GCC 12 reports a false -Wmaybe-uninitialized inside std::variant<..., std::string> when the
// key table is built (GCC bug 107138 and relatives); the table is plain constant data.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

namespace weedspray::daemon::key_tables {

void append_operation_keys(std::vector<KeySpec<Config>>& keys) {
  // clang-format off
  keys.insert(keys.end(), {
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
     "segmentation network in model, its scores interpolated to the camera's pixels; hybrid: "
     "colour vegetation minus the network's crop class "
     "grown by crop_margin_cm; plants: colour vegetation at the camera's resolution, each "
     "connected plant crop or weed by the network's votes (plants the network cannot resolve "
     "are weed; see min_plant_cm2); dnn_vegetation: the network's classes, but in the outer "
     "network pixel of each plant soil wherever colour finds no vegetation within about a "
     "millimetre (the network's scores are coarser than a leaf's edge, colour draws the edge). "
     "The rate law uses each zone's weed density",
     {"vegetation", "inter_row", "dnn", "hybrid", "plants", "dnn_vegetation"}},
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
    {WS_KEY(vision, model), std::string("weed-peanut-2mm.onnx"), 0, 0, "path",
     "dnn, hybrid, plants, dnn_vegetation: the segmentation network, an ONNX file OpenCV DNN loads (checked with one "
     "forward pass at load), with its spec in NAME.json beside it (input size, normalisation, "
     "channel order, classes, the ground scale it learnt at, training data and licence; "
     "tools/train/train.py writes it). A relative path is looked up beside the configuration "
     "file that sets it, then among the installed models (/usr/share/weedspray/models from the "
     "package; a build tree also looks in its checkout's models/). The default is the shipped "
     "crop/weed/soil model trained on peanut fields, fed 2 mm of ground per pixel with scores "
     "every 4 mm, which keeps up with a camera that sees about 1 mm per pixel (also shipped: "
     "weed-peanut-4mm.onnx, fed and deciding at 4 and 8 mm, faster and blind to more small "
     "weeds; weed-peanut.onnx, learnt at 0.94 mm per network pixel, for cameras closer to the "
     "ground); train one for your crop with "
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
     "above this duty the valve is held fully open; with the nozzle's held-open flow metered "
     "(calibrate nozzles), a flow between this duty's and the held-open one alternates whole "
     "PWM periods held open and at this duty, so that their mean is the flow"},
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
  });
  // clang-format on
}

}  // namespace weedspray::daemon::key_tables
