// SPDX-License-Identifier: Apache-2.0
// The configuration key table, parser and default file.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"
#include "io/signal_conversion.hpp"
#include "vision/threshold.hpp"
#include "vision/vegetation_index.hpp"

namespace weedspray::daemon {
namespace {

namespace fs = std::filesystem;

Config parse(const std::string& text, const std::string& name = "test.toml") {
  return load_config_from_strings({{name, text}});
}

// Expects a ConfigError and returns it.
ConfigError parse_error(const std::vector<std::pair<std::string, std::string>>& documents) {
  try {
    (void)load_config_from_strings(documents);
  } catch (const ConfigError& error) {
    return error;
  }
  ADD_FAILURE() << "no ConfigError";
  return ConfigError("", 0, "", "");
}

// A valid value different from the default, as TOML text, and the value it must read back as.
template <class Root>
std::pair<std::string, DefaultValue> other_value(const KeySpec<Root>& spec) {
  std::ostringstream text;
  text.precision(17);
  switch (spec.type()) {
    case KeyType::kBool: {
      const bool v = !std::get<bool>(spec.default_value);
      return {v ? "true" : "false", v};
    }
    case KeyType::kInt: {
      const int d = std::get<int>(spec.default_value);
      const int v = d + 1 <= spec.max ? d + 1 : d - 1;
      return {std::to_string(v), v};
    }
    case KeyType::kDouble: {
      const double d = std::get<double>(spec.default_value);
      const double v = d < spec.max ? d + (spec.max - d) * 0.01 : d - (d - spec.min) * 0.01;
      text << v;
      std::string s = text.str();
      if (s.find_first_of(".e") == std::string::npos) s += ".0";
      return {s, v};
    }
    case KeyType::kString:
      return {"\"round-trip-value\"", std::string("round-trip-value")};
    case KeyType::kEnum: {
      const std::string d = std::get<std::string>(spec.default_value);
      for (auto choice : spec.choices) {
        if (choice != d) return {"\"" + std::string(choice) + "\"", std::string(choice)};
      }
      return {"\"" + d + "\"", d};
    }
    case KeyType::kIntList: {
      // One line per nozzle of the default boom.
      std::vector<int> v{5, 6, 7, 8};
      return {"[5, 6, 7, 8]", v};
    }
    case KeyType::kStringList: {
      std::vector<std::string> v{"v0", "v1", "v2", "v3"};
      return {"[\"v0\", \"v1\", \"v2\", \"v3\"]", v};
    }
    case KeyType::kDoubleList: {
      std::vector<double> v{1.5, 2.5, 3.5};
      return {"[1.5, 2.5, 3.5]", v};
    }
  }
  return {};
}

template <class Root>
DefaultValue read_back(const KeySpec<Root>& spec, Root& root) {
  return std::visit([&](auto access) -> DefaultValue { return access(root); }, spec.field);
}

TEST(ConfigSchema, EveryDefaultHasTheKeysTypeAndIsInRange) {
  const auto check = [](const auto& spec) {
    SCOPED_TRACE(spec.full_name());
    EXPECT_FALSE(spec.doc.empty());
    const auto field = spec.field.index();
    const auto value = spec.default_value.index();
    EXPECT_EQ(field, value) << "default's type differs from the member's";
    if (spec.type() == KeyType::kInt) {
      EXPECT_GE(std::get<int>(spec.default_value), spec.min);
      EXPECT_LE(std::get<int>(spec.default_value), spec.max);
    }
    if (spec.type() == KeyType::kDouble) {
      EXPECT_GE(std::get<double>(spec.default_value), spec.min);
      EXPECT_LE(std::get<double>(spec.default_value), spec.max);
    }
    if (spec.type() == KeyType::kEnum) {
      const auto& d = std::get<std::string>(spec.default_value);
      EXPECT_NE(std::find(spec.choices.begin(), spec.choices.end(), d), spec.choices.end());
    }
  };
  for (const auto& spec : config_keys()) check(spec);
  for (const auto& spec : camera_keys()) check(spec);
}

TEST(ConfigSchema, KeysAreDeclaredOnce) {
  std::set<std::string> names;
  for (const auto& spec : config_keys()) EXPECT_TRUE(names.insert(spec.full_name()).second);
  for (const auto& spec : camera_keys()) EXPECT_TRUE(names.insert(spec.full_name()).second);
}

TEST(ConfigSchema, EveryKeyRoundTrips) {
  for (const auto& spec : config_keys()) {
    SCOPED_TRACE(spec.full_name());
    const auto [text, expected] = other_value(spec);
    // Appended piece by piece: GCC 12's -Wrestrict misfires (bug 105329) on the chain of
    // operator+ with a literal on the left when it is inlined at -O3 (the arm64 build).
    std::string toml = "[";
    toml.append(spec.section)
        .append("]\n")
        .append(spec.name)
        .append(" = ")
        .append(text)
        .append("\n");
    Config config = parse(toml);
    EXPECT_EQ(read_back(spec, config), expected);
    EXPECT_EQ(config.sources.at(spec.full_name()).line, 2);
  }
  for (const auto& spec : camera_keys()) {
    SCOPED_TRACE(spec.full_name());
    const auto [text, expected] = other_value(spec);
    Config config =
        parse("[boom]\nnozzles = 8\n[[camera]]\n" + std::string(spec.name) + " = " + text + "\n");
    ASSERT_EQ(config.cameras.size(), 1U);
    EXPECT_EQ(read_back(spec, config.cameras[0]), expected);
  }
}

TEST(ConfigSchema, DumpParsesBackToTheSameConfiguration) {
  Config original = parse(
      "[pressure]\nsetpoint_mpa = 0.25\n[boom]\nnozzles = 6\n"
      "[[camera]]\nnozzle_count = 3\n[[camera]]\nfirst_nozzle = 3\n"
      "nozzle_count = 3\n");
  Config again = parse(dump_config(original), "dump.toml");
  for (const auto& spec : config_keys()) {
    EXPECT_EQ(read_back(spec, again), read_back(spec, original)) << spec.full_name();
  }
  ASSERT_EQ(again.cameras.size(), 2U);
  EXPECT_EQ(again.cameras[1].first_nozzle, 3);
}

TEST(ConfigSchema, VisionChoicesAreTheVisionLibrarysNames) {
  for (const auto& spec : config_keys()) {
    if (spec.full_name() == "vision.index") {
      for (auto choice : spec.choices) {
        if (choice != "default") {
          EXPECT_TRUE(vision::parse_vegetation_index(choice)) << choice;
        }
      }
    }
    if (spec.full_name() == "vision.threshold") {
      for (auto choice : spec.choices) {
        if (choice != "default") {
          EXPECT_TRUE(vision::parse_threshold_method(choice)) << choice;
        }
      }
    }
  }
}

TEST(ConfigErrors, UnknownKeyNamesFileLineAndKey) {
  const auto e = parse_error({{"main.toml", "[pressure]\nsetpoint_mpa = 0.3\nsetpiont = 1\n"}});
  EXPECT_EQ(e.file(), "main.toml");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "pressure.setpiont");
  EXPECT_NE(std::string(e.what()).find("main.toml:3: pressure.setpiont: unknown key"),
            std::string::npos)
      << e.what();
}

// Hardware mode needs the heartbeat (the relay that cuts valves and pump outside the process),
// or the explicit opt-out.
TEST(ConfigErrors, HardwareWithoutAHeartbeatIsRefusedAtTheGpioSection) {
  const Config config =
      load_config_from_strings({{"main.toml", "[boom]\nnozzles = 4\n[gpio]\nchip = \"x\"\n"}});
  try {
    (void)require_heartbeat(config);
    FAIL() << "accepted without a heartbeat";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), "main.toml");
    EXPECT_EQ(e.line(), 4);
    EXPECT_EQ(e.key(), "gpio.heartbeat_name");
    EXPECT_NE(std::string(e.what()).find("hardware mode needs a heartbeat output"),
              std::string::npos)
        << e.what();
  }
}

TEST(ConfigErrors, HeartbeatSetToNoneIsRefusedThere) {
  const Config config =
      load_config_from_strings({{"main.toml", "[gpio]\n\nheartbeat_offset = -1\n"}});
  try {
    (void)require_heartbeat(config);
    FAIL() << "accepted without a heartbeat";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.key(), "gpio.heartbeat_offset");
  }
}

TEST(ConfigErrors, HeartbeatOrItsOptOutLetsHardwareStart) {
  EXPECT_FALSE(require_heartbeat(
      load_config_from_strings({{"main.toml", "[gpio]\nheartbeat_name = \"HB\"\n"}})));
  EXPECT_FALSE(require_heartbeat(
      load_config_from_strings({{"main.toml", "[gpio]\nheartbeat_offset = 7\n"}})));
  // The opt-out allows the start and says so (the caller warns).
  EXPECT_TRUE(require_heartbeat(
      load_config_from_strings({{"main.toml", "[gpio]\nheartbeat_opt_out = true\n"}})));
}

// Hardware mode needs the emergency-stop input too, or its explicit opt-out.
TEST(ConfigErrors, HardwareWithoutAnEstopIsRefusedAtItsKey) {
  const Config config = load_config_from_strings(
      {{"main.toml", "[gpio]\nheartbeat_name = \"HB\"\n\nestop_offset = -1\n"}});
  try {
    (void)require_estop(config);
    FAIL() << "accepted without an E-stop";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.line(), 4);
    EXPECT_EQ(e.key(), "gpio.estop_offset");
    EXPECT_NE(std::string(e.what()).find("hardware mode needs an emergency-stop input"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(
      require_estop(load_config_from_strings({{"main.toml", "[gpio]\nestop_name = \"ESTOP\"\n"}})));
  EXPECT_FALSE(
      require_estop(load_config_from_strings({{"main.toml", "[gpio]\nestop_offset = 3\n"}})));
  EXPECT_TRUE(
      require_estop(load_config_from_strings({{"main.toml", "[gpio]\nestop_opt_out = true\n"}})));
}

TEST(ConfigErrors, UnknownSection) {
  const auto e = parse_error({{"main.toml", "\n[presure]\nsetpoint_mpa = 0.3\n"}});
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "presure");
}

TEST(ConfigErrors, WrongType) {
  const auto e = parse_error({{"main.toml", "[boom]\nnozzles = \"four\"\n"}});
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "boom.nozzles");
  EXPECT_NE(std::string(e.what()).find("expected integer, got string"), std::string::npos);
  const auto f = parse_error({{"main.toml", "[boom]\nnozzles = 4.5\n"}});
  EXPECT_EQ(f.key(), "boom.nozzles");
  const auto g = parse_error({{"main.toml", "[daemon]\nautostart = 1\n"}});
  EXPECT_EQ(g.key(), "daemon.autostart");
}

TEST(ConfigErrors, OutOfRangeSaysRangeAndUnit) {
  const auto e = parse_error({{"main.toml", "[pressure]\n\nsetpoint_mpa = 5.0\n"}});
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.key(), "pressure.setpoint_mpa");
  EXPECT_NE(std::string(e.what()).find("5 is outside 0.05..1 MPa"), std::string::npos) << e.what();
}

TEST(ConfigErrors, BadChoiceListsTheChoices) {
  const auto e = parse_error({{"main.toml", "[pressure]\ncontroller = \"fuzzy\"\n"}});
  EXPECT_EQ(e.key(), "pressure.controller");
  EXPECT_NE(std::string(e.what()).find("\"fuzzy_pid\", \"pid\""), std::string::npos) << e.what();
}

TEST(ConfigErrors, TomlSyntaxErrorHasTheLine) {
  const auto e = parse_error({{"main.toml", "[pressure]\nsetpoint_mpa = 0.3\n[boom\n"}});
  EXPECT_EQ(e.file(), "main.toml");
  EXPECT_EQ(e.line(), 3);
}

// Every problem of every file at once, each file's in line order, located at the first; a
// file that does not parse does not hide the next file's problems. Rules between keys wait
// until every value parsed.
TEST(ConfigErrors, EveryProblemIsListedAtOnce) {
  const auto e =
      parse_error({{"main.toml",
                    "[pwm]\nfrequency_hz = 50\nstaggered = \"yes\"\n[gpio]\nvalve_ofsets = [1]\n"
                    "[nonsense]\na = 1\n"},
                   {"conf.d/10-broken.toml", "[boom\n"},
                   {"conf.d/20-camera.toml", "[[camera]]\nfps = -1\n"}});
  EXPECT_EQ(e.file(), "main.toml");
  EXPECT_EQ(e.line(), 2);
  EXPECT_EQ(e.key(), "pwm.frequency_hz");
  const std::vector<std::string> expected = {
      "main.toml:2: pwm.frequency_hz: 50 is outside",
      "main.toml:3: pwm.staggered: expected",
      "main.toml:5: gpio.valve_ofsets: unknown key",
      "main.toml:6: nonsense: unknown section",
      "conf.d/10-broken.toml:1: ",
      "conf.d/20-camera.toml:2: camera[0].fps: -1 is outside"};
  std::istringstream lines(e.what());
  std::size_t n = 0;
  for (std::string line; std::getline(lines, line); ++n) {
    ASSERT_LT(n, expected.size()) << e.what();
    EXPECT_EQ(line.rfind(expected[n], 0), 0U) << line;
  }
  EXPECT_EQ(n, expected.size()) << e.what();
  // One problem: its own text, as before.
  const auto one = parse_error({{"main.toml", "[boom]\nnozzles = 0\n"}});
  EXPECT_EQ(std::string(one.what()).find('\n'), std::string::npos) << one.what();
}

TEST(ConfigErrors, CrossKeyRulesNameTheKeyAndWhereItWasSet) {
  const auto e = parse_error({{"main.toml", "[boom]\nnozzles = 4\n"},
                              {"conf.d/10-cam.toml", "[[camera]]\nfirst_nozzle = 2\n"}});
  EXPECT_EQ(e.file(), "conf.d/10-cam.toml");
  EXPECT_EQ(e.key(), "camera[0].nozzle_count");
  const auto f = parse_error({{"main.toml", "[spray]\nduty_min_pct = 50\nduty_max_pct = 40\n"}});
  EXPECT_EQ(f.key(), "spray.duty_max_pct");
  EXPECT_EQ(f.line(), 3);
  const auto g =
      parse_error({{"main.toml", "[boom]\nnozzles = 4\n[gpio]\nvalve_offsets = [1, 2]\n"}});
  EXPECT_EQ(g.key(), "gpio.valve_offsets");
  const auto h = parse_error({{"main.toml",
                               "[boom]\nnozzles = 4\n[[camera]]\nnozzle_count = 3\n[[camera]]\n"
                               "first_nozzle = 2\nnozzle_count = 2\n"}});
  EXPECT_EQ(h.key(), "camera[1].first_nozzle");
  const auto both_valves = parse_error(
      {{"main.toml",
        "[gpio]\nvalve_offsets = [1, 2, 3, 4]\nvalve_names = [\"a\", \"b\", \"c\", \"d\"]\n"}});
  EXPECT_EQ(both_valves.key(), "gpio.valve_names");
  EXPECT_EQ(both_valves.line(), 3);
  const auto both_pump =
      parse_error({{"main.toml", "[gpio]\npump_offset = 5\npump_name = \"pump\"\n"}});
  EXPECT_EQ(both_pump.key(), "gpio.pump_name");
  const auto not_strings = parse_error({{"main.toml", "[gpio]\nvalve_names = [\"a\", 2]\n"}});
  EXPECT_EQ(not_strings.key(), "gpio.valve_names");
}

TEST(ConfigDose, TargetRateInLitresPerHectareSetsTheNominalFlow) {
  // 205 L/ha over 0.5 m at 1 m/s: 205 / 10000 x 60 x 0.5 x 1 = 0.615 L/min per nozzle.
  const Config c = parse("[spray]\ntarget_rate_l_per_ha = 205\n");
  EXPECT_NEAR(c.spray.nominal_flow_l_per_min, 0.615, 1e-12);
  const Config wide_fast = parse(
      "[boom]\nnozzle_width_m = 0.25\n[spray]\ntarget_rate_l_per_ha = 100\n"
      "nominal_speed_m_per_s = 2.0\n");
  EXPECT_NEAR(wide_fast.spray.nominal_flow_l_per_min, 0.3, 1e-12);
  // Off (0): the flow key stands.
  EXPECT_NEAR(parse("[spray]\nnominal_flow_l_per_min = 0.8\n").spray.nominal_flow_l_per_min, 0.8,
              1e-12);
}

TEST(ConfigDose, ATargetRateThatDisagreesWithTheFlowOrNoNozzleCanGiveIsRefused) {
  const auto both = parse_error(
      {{"main.toml", "[spray]\nnominal_flow_l_per_min = 0.8\ntarget_rate_l_per_ha = 205\n"}});
  EXPECT_EQ(both.key(), "spray.target_rate_l_per_ha");
  EXPECT_EQ(both.line(), 3);
  EXPECT_NE(std::string(both.what()).find("nominal_flow_l_per_min"), std::string::npos);
  // 5000 L/ha at 10 m/s over 3 m: 900 L/min per nozzle.
  const auto too_much =
      parse_error({{"main.toml",
                    "[boom]\nnozzle_width_m = 3\n[spray]\nnominal_speed_m_per_s = 10\n"
                    "target_rate_l_per_ha = 5000\n"}});
  EXPECT_EQ(too_much.key(), "spray.target_rate_l_per_ha");
  EXPECT_NE(std::string(too_much.what()).find("900 L/min"), std::string::npos) << too_much.what();
  // --dump-config writes both keys, in agreement: it parses back.
  const Config c = parse("[spray]\ntarget_rate_l_per_ha = 150\n");
  EXPECT_NO_THROW(parse(dump_config(c)));
}

// The pressure sensor's trip limits cannot be configured so that a cut wire reads as a
// pressure, a short as a valid reading, or an over-pressure trip lies beyond what the sensor
// can read.
TEST(ConfigTripLimits, ACutWireIsAlwaysASensorFault) {
  const auto& low = config_key("alarms.sensor_fault_low_ma");
  // A cut wire reads 0 mA; leakage and ADC offset leave it within about 1 mA. At the most
  // permissive limit allowed the conversion still calls both an open circuit.
  io::CurrentLoopSensorConfig sensor;
  sensor.fault_below_ma = low.min;
  for (double cut_ma : {0.0, 1.0}) {
    const auto reading =
        io::pressure_from_sensor_volts(io::volts_from_current_ma(cut_ma, sensor), sensor);
    EXPECT_EQ(reading.status, io::SensorStatus::kOpenCircuit) << cut_ma << " mA";
  }
  EXPECT_GE(low.min, 3.0);
  EXPECT_LE(low.max, 3.8);  // the bottom of NAMUR NE 43's measuring range stays valid
  const auto zero = parse_error({{"main.toml", "[alarms]\n\nsensor_fault_low_ma = 0\n"}});
  EXPECT_EQ(zero.key(), "alarms.sensor_fault_low_ma");
  EXPECT_EQ(zero.line(), 3);
  EXPECT_NE(std::string(zero.what()).find("0 is outside 3..3.8 mA"), std::string::npos)
      << zero.what();
  EXPECT_EQ(parse_error({{"main.toml", "[alarms]\nsensor_fault_low_ma = 1.0\n"}}).key(),
            "alarms.sensor_fault_low_ma");
  EXPECT_EQ(parse_error({{"main.toml", "[alarms]\nsensor_fault_low_ma = 3.9\n"}}).key(),
            "alarms.sensor_fault_low_ma");
  EXPECT_EQ(parse("[alarms]\nsensor_fault_low_ma = 3.0\n").alarms.sensor_fault_low_ma, 3.0);
  EXPECT_EQ(parse("[alarms]\nsensor_fault_low_ma = 3.8\n").alarms.sensor_fault_low_ma, 3.8);
}

TEST(ConfigTripLimits, AShortedSensorIsAlwaysAFault) {
  const auto& high = config_key("alarms.sensor_fault_high_ma");
  EXPECT_GE(high.min, 20.5);  // the top of the measuring range stays valid
  // A shorted loop (the simulator's 24 mA) is above every allowed limit.
  io::CurrentLoopSensorConfig sensor;
  sensor.fault_above_ma = high.max;
  EXPECT_EQ(io::pressure_from_sensor_volts(io::volts_from_current_ma(24.0, sensor), sensor).status,
            io::SensorStatus::kShortCircuit);
  EXPECT_EQ(parse_error({{"main.toml", "[alarms]\nsensor_fault_high_ma = 20.0\n"}}).key(),
            "alarms.sensor_fault_high_ma");
  EXPECT_EQ(parse_error({{"main.toml", "[alarms]\nsensor_fault_high_ma = 30\n"}}).key(),
            "alarms.sensor_fault_high_ma");
  EXPECT_EQ(parse("[alarms]\nsensor_fault_high_ma = 20.5\n").alarms.sensor_fault_high_ma, 20.5);
}

TEST(ConfigTripLimits, OverPressureTripLiesBelowTheSensorsFullScale) {
  // At the full scale (1 MPa at 20 mA by default): refused, naming the trip where it was set.
  const auto at = parse_error({{"main.toml", "[alarms]\nover_pressure_mpa = 1.0\n"}});
  EXPECT_EQ(at.key(), "alarms.over_pressure_mpa");
  EXPECT_EQ(at.line(), 2);
  EXPECT_NE(std::string(at.what()).find("must be below pressure.sensor_max_mpa (1 MPa"),
            std::string::npos)
      << at.what();
  EXPECT_EQ(parse_error({{"main.toml", "[alarms]\nover_pressure_mpa = 5\n"}}).key(),
            "alarms.over_pressure_mpa");
  // A smaller sensor under the default trip: the sensor's key is named, in its drop-in.
  const auto small = parse_error(
      {{"main.toml", "[boom]\nnozzles = 4\n"},
       {"conf.d/20-sensor.toml", "[pressure]\nsensor_max_mpa = 0.6\nsetpoint_mpa = 0.3\n"}});
  EXPECT_EQ(small.key(), "pressure.sensor_max_mpa");
  EXPECT_EQ(small.file(), "conf.d/20-sensor.toml");
  EXPECT_EQ(small.line(), 2);
  const Config bigger =
      parse("[pressure]\nsensor_max_mpa = 2.5\n[alarms]\nover_pressure_mpa = 2\n");
  EXPECT_EQ(bigger.alarms.over_pressure_mpa, 2.0);
  EXPECT_NO_THROW(
      parse("[pressure]\nsensor_max_mpa = 0.6\nsetpoint_mpa = 0.3\n[alarms]\n"
            "over_pressure_mpa = 0.55\nblocked_pressure_mpa = 0.5\n"));
}

// Nozzle health needs staggered phase windows long enough to outlast the meter's lag.
TEST(ConfigErrors, NozzleHealthNeedsSeparableWindows) {
  const Config ok = parse("[nozzle_health]\nenabled = true\nbaseline_s = 20\n");
  EXPECT_TRUE(ok.nozzle_health.enabled);
  EXPECT_EQ(ok.nozzle_health.baseline_s, 20.0);
  const auto synchronous =
      parse_error({{"main.toml", "[pwm]\nstaggered = false\n[nozzle_health]\nenabled = true\n"}});
  EXPECT_EQ(synchronous.key(), "nozzle_health.enabled");
  EXPECT_EQ(synchronous.line(), 4);
  // 20 Hz x 4 nozzles: 12.5 ms windows, shorter than the 30 ms meter lag.
  const auto short_windows =
      parse_error({{"main.toml", "[pwm]\nfrequency_hz = 20\n[nozzle_health]\nenabled = true\n"}});
  EXPECT_EQ(short_windows.key(), "nozzle_health.enabled");
  EXPECT_NO_THROW(parse("[pwm]\nstaggered = false\n"));  // off: no rule
}

// The judge: band by default (the daemon's behaviour before the CUSUM), cusum on request with
// its threshold; anything else is refused naming the key.
TEST(ConfigErrors, NozzleHealthJudge) {
  EXPECT_EQ(parse("[nozzle_health]\nenabled = true\n").nozzle_health.judge, "band");
  const Config cusum =
      parse("[nozzle_health]\nenabled = true\njudge = \"cusum\"\nalarm_threshold = 30\n");
  EXPECT_EQ(cusum.nozzle_health.judge, "cusum");
  EXPECT_EQ(cusum.nozzle_health.alarm_threshold, 30.0);
  EXPECT_EQ(parse_error({{"main.toml", "[nozzle_health]\njudge = \"glr\"\n"}}).key(),
            "nozzle_health.judge");
  EXPECT_EQ(parse_error({{"main.toml", "[nozzle_health]\nalarm_threshold = 0\n"}}).key(),
            "nozzle_health.alarm_threshold");
}

TEST(ConfigSchema, GpioLinesByName) {
  Config config = parse(
      "[gpio]\nvalve_names = [\"valve0\", \"valve1\", \"valve2\", \"valve3\"]\n"
      "flow_name = \"flow\"\n");
  EXPECT_EQ(config.gpio.valve_names.size(), 4U);
  EXPECT_EQ(config.gpio.valve_names[3], "valve3");
  EXPECT_EQ(config.gpio.flow_name, "flow");
  EXPECT_EQ(config.gpio.flow_offset, -1);
}

TEST(ConfigSchema, ModbusAnalogModulesOnTheirOwnBus) {
  const Config config = parse(
      "[adc]\nsource = \"modbus\"\nmodbus_slave_id = 5\nmodbus_register_type = \"holding\"\n"
      "[dac]\nsource = \"modbus\"\nmodbus_register = 1\n"
      "[analog_modbus]\ndevice = \"/dev/ttyAMA1\"\nbaud = 57600\n");
  EXPECT_EQ(config.adc.source, "modbus");
  EXPECT_EQ(config.adc.modbus_slave_id, 5);
  EXPECT_EQ(config.adc.modbus_register_type, "holding");
  EXPECT_EQ(config.dac.source, "modbus");
  EXPECT_EQ(config.analog_modbus.device, "/dev/ttyAMA1");
  EXPECT_EQ(config.analog_modbus.baud, 57600);

  // The tank sensor's port is polled by another thread.
  const auto shared_port =
      parse_error({{"main.toml",
                    "[modbus]\nenabled = true\ndevice = \"/dev/ttyUSB0\"\n"
                    "[adc]\nsource = \"modbus\"\n[analog_modbus]\ndevice = \"/dev/ttyUSB0\"\n"}});
  EXPECT_EQ(shared_port.key(), "analog_modbus.device");
  EXPECT_EQ(shared_port.line(), 7);
  EXPECT_NE(std::string(shared_port.what()).find("tank sensor"), std::string::npos)
      << shared_port.what();
  // Too slow a bus for the loop: 9600 baud needs ~25 ms, 100 Hz leaves 5 ms.
  const auto slow =
      parse_error({{"main.toml", "[dac]\nsource = \"modbus\"\n[analog_modbus]\nbaud = 9600\n"}});
  EXPECT_EQ(slow.key(), "analog_modbus.baud");
  EXPECT_NE(std::string(slow.what()).find("pressure.loop_hz"), std::string::npos) << slow.what();
  EXPECT_NO_THROW(
      (void)parse("[dac]\nsource = \"modbus\"\n[analog_modbus]\nbaud = 9600\n"
                  "[pressure]\nloop_hz = 10\n"));
  // IIO converters do not care about the analog bus.
  EXPECT_NO_THROW((void)parse("[analog_modbus]\nbaud = 9600\n"));
  const auto same_register = parse_error(
      {{"main.toml",
        "[adc]\nsource = \"modbus\"\nmodbus_slave_id = 3\nmodbus_register_type = \"holding\"\n"
        "[dac]\nsource = \"modbus\"\n"}});
  EXPECT_EQ(same_register.key(), "dac.modbus_register");
}

TEST(ConfigSchema, ModbusDacWatchdogFitsItsRegisterAndTheLoop) {
  const Config armed = parse(
      "[dac]\nsource = \"modbus\"\nmodbus_comm_timeout_register = 40\n"
      "modbus_comm_timeout_s = 0.3\nmodbus_safe_value_register = 41\n");
  EXPECT_EQ(armed.dac.modbus_comm_timeout_register, 40);
  EXPECT_EQ(armed.dac.modbus_safe_value_register, 41);
  // 120 s in milliseconds does not fit a 16-bit register.
  const auto too_long =
      parse_error({{"main.toml",
                    "[dac]\nsource = \"modbus\"\nmodbus_comm_timeout_register = 40\n"
                    "modbus_comm_timeout_s = 60\nmodbus_comm_timeout_counts_per_s = 10000\n"}});
  EXPECT_EQ(too_long.key(), "dac.modbus_comm_timeout_s");
  EXPECT_NE(std::string(too_long.what()).find("1..65535"), std::string::npos) << too_long.what();
  // At 10 Hz the value is rewritten every 0.1 s at best: a 0.2 s timeout would expire.
  const auto too_short = parse_error(
      {{"main.toml",
        "[dac]\nsource = \"modbus\"\nmodbus_comm_timeout_register = 40\n"
        "modbus_comm_timeout_s = 0.2\n[pressure]\nloop_hz = 10\n[analog_modbus]\nbaud = 9600\n"}});
  EXPECT_EQ(too_short.key(), "dac.modbus_comm_timeout_s");
  EXPECT_NE(std::string(too_short.what()).find("6 periods"), std::string::npos) << too_short.what();
  const auto clash =
      parse_error({{"main.toml", "[dac]\nsource = \"modbus\"\nmodbus_safe_value_register = 0\n"}});
  EXPECT_EQ(clash.key(), "dac.modbus_register");
  // An IIO DAC ignores the Modbus keys.
  EXPECT_NO_THROW((void)parse("[dac]\nmodbus_comm_timeout_register = 0\n"));
}

TEST(ConfigSchema, FlowMeterOnAKernelCounterOrAGpioLineNotBoth) {
  EXPECT_EQ(parse("[flow]\ncounter = \"weedspray-flow\"\n").flow.counter, "weedspray-flow");
  const auto both =
      parse_error({{"main.toml", "[gpio]\nflow_offset = 4\n[flow]\ncounter = \"counter0\"\n"}});
  EXPECT_EQ(both.key(), "flow.counter");
  EXPECT_EQ(both.line(), 4);
}

TEST(ConfigSchema, GnssSpeedNeedsTheReceiverEnabled) {
  const Config config = parse("[gnss]\nenabled = true\nport = 2948\n[speed]\nsource = \"gnss\"\n");
  EXPECT_EQ(config.speed.source, "gnss");
  EXPECT_EQ(config.gnss.port, 2948);
  const auto off =
      parse_error({{"main.toml", "[wheel]\nsource = \"fixed\"\n[speed]\nsource = \"gnss\"\n"}});
  EXPECT_EQ(off.key(), "speed.source");
  EXPECT_EQ(off.line(), 4);
  EXPECT_NE(std::string(off.what()).find("gnss.enabled"), std::string::npos) << off.what();
}

TEST(ConfigSchema, ImuYawSourceNeedsItsDevice) {
  const Config config =
      parse("[turn]\nyaw_source = \"imu\"\nimu_device = \"mpu6050\"\nimu_axis = \"x\"\n");
  EXPECT_EQ(config.turn.imu_device, "mpu6050");
  EXPECT_EQ(config.turn.imu_axis, "x");
  EXPECT_TRUE(config.turn.imu_axis_up);
  const auto missing = parse_error({{"main.toml", "[turn]\nyaw_source = \"imu\"\n"}});
  EXPECT_EQ(missing.key(), "turn.yaw_source");
  EXPECT_EQ(missing.line(), 2);
  EXPECT_NE(std::string(missing.what()).find("turn.imu_device"), std::string::npos)
      << missing.what();
  const auto axis = parse_error({{"main.toml", "[turn]\nimu_axis = \"w\"\n"}});
  EXPECT_EQ(axis.key(), "turn.imu_axis");
}

TEST(ConfigSchema, FleetNamesAreTopicLevels) {
  const Config config = parse("[fleet]\nmachine = \"north-field_2\"\nboard = \"left\"\n");
  EXPECT_EQ(config.fleet.machine, "north-field_2");
  EXPECT_FALSE(config.fleet.enabled);
  EXPECT_EQ(config.fleet.commands, "operator");
  for (const char* bad : {"a/b", "#", "+", "", "two words"}) {
    SCOPED_TRACE(bad);
    const auto error =
        parse_error({{"main.toml", std::string("[fleet]\nboard = \"") + bad + "\"\n"}});
    EXPECT_EQ(error.key(), "fleet.board");
    EXPECT_EQ(error.line(), 2);
  }
}

TEST(ConfigSchema, FleetPictureIntervalRange) {
  EXPECT_DOUBLE_EQ(parse("").fleet.picture_interval_s, 5.0);
  EXPECT_DOUBLE_EQ(parse("[fleet]\npicture_interval_s = 0\n").fleet.picture_interval_s, 0.0);
  EXPECT_DOUBLE_EQ(parse("[fleet]\npicture_interval_s = 0.5\n").fleet.picture_interval_s, 0.5);
  for (const char* bad : {"-1", "3601"}) {
    SCOPED_TRACE(bad);
    const auto error =
        parse_error({{"main.toml", std::string("[fleet]\npicture_interval_s = ") + bad + "\n"}});
    EXPECT_EQ(error.key(), "fleet.picture_interval_s");
    EXPECT_EQ(error.line(), 2);
  }
}

TEST(ConfigSchema, FleetGnssComesWithTheFleetSpeed) {
  EXPECT_EQ(parse("").gnss.source, "gpsd");
  const Config config = parse(
      "[speed]\nsource = \"fleet\"\n[fleet]\nspeed_from = \"left\"\n[gnss]\nenabled = true\n"
      "source = \"fleet\"\n");
  EXPECT_EQ(config.gnss.source, "fleet");
  const auto alone = parse_error({{"main.toml", "[gnss]\nenabled = true\nsource = \"fleet\"\n"}});
  EXPECT_EQ(alone.key(), "gnss.source");
  EXPECT_EQ(alone.line(), 3);
  EXPECT_NE(std::string(alone.what()).find("speed.source"), std::string::npos) << alone.what();
}

TEST(ConfigSchema, FleetSpeedNeedsTheBoardItComesFrom) {
  const Config config = parse(
      "[speed]\nsource = \"fleet\"\nshared_timeout_s = 0.3\n[fleet]\nspeed_from = \"left\"\n");
  EXPECT_EQ(config.speed.source, "fleet");
  EXPECT_DOUBLE_EQ(config.speed.shared_timeout_s, 0.3);
  EXPECT_EQ(config.fleet.speed_from, "left");
  EXPECT_DOUBLE_EQ(parse("").speed.shared_timeout_s, 0.5);
  EXPECT_DOUBLE_EQ(parse("").fleet.motion_rate_hz, 0.0);
  const auto none = parse_error({{"main.toml", "[speed]\nsource = \"fleet\"\n"}});
  EXPECT_EQ(none.key(), "speed.source");
  EXPECT_EQ(none.line(), 2);
  EXPECT_NE(std::string(none.what()).find("fleet.speed_from"), std::string::npos) << none.what();
  const auto itself =
      parse_error({{"main.toml", "[fleet]\nboard = \"left\"\nspeed_from = \"left\"\n"}});
  EXPECT_EQ(itself.key(), "fleet.speed_from");
  const auto not_a_level = parse_error({{"main.toml", "[fleet]\nspeed_from = \"a/b\"\n"}});
  EXPECT_EQ(not_a_level.key(), "fleet.speed_from");
  // The timeout's floor and ceiling: a loss noticed within 2 s at most, never on jitter alone.
  for (const char* bad : {"0.05", "2.5"}) {
    SCOPED_TRACE(bad);
    const auto error =
        parse_error({{"main.toml", std::string("[speed]\nshared_timeout_s = ") + bad + "\n"}});
    EXPECT_EQ(error.key(), "speed.shared_timeout_s");
  }
}

class ConfigFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weedspray-config-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "conf.d");
  }
  void TearDown() override { fs::remove_all(dir_); }
  void write(const fs::path& relative, const std::string& text) {
    std::ofstream(dir_ / relative) << text;
  }
  fs::path dir_;
};

TEST_F(ConfigFiles, DropInsAreReadInNameOrderAndLaterWins) {
  write("weedspray.toml", "[pressure]\nsetpoint_mpa = 0.2\n");
  write("conf.d/20-late.toml", "[pressure]\nsetpoint_mpa = 0.35\n");
  write("conf.d/10-early.toml", "[pressure]\nsetpoint_mpa = 0.3\n[boom]\nnozzles = 6\n");
  write("conf.d/README", "not toml, ignored");
  const Config config = load_config(dir_ / "weedspray.toml");
  EXPECT_DOUBLE_EQ(config.pressure.setpoint_mpa, 0.35);
  EXPECT_EQ(config.boom.nozzles, 6);
  ASSERT_EQ(config.files.size(), 3U);
  EXPECT_NE(config.files[1].find("10-early.toml"), std::string::npos);
  EXPECT_NE(config.sources.at("pressure.setpoint_mpa").file.find("20-late.toml"),
            std::string::npos);
}

TEST_F(ConfigFiles, BadDropInIsNamed) {
  write("weedspray.toml", "[pressure]\nsetpoint_mpa = 0.2\n");
  write("conf.d/50-bad.toml", "[pressure]\n# comment\nsetpoint_mpa = -1\n");
  try {
    (void)load_config(dir_ / "weedspray.toml");
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(e.file().find("conf.d/50-bad.toml"), std::string::npos);
    EXPECT_EQ(e.line(), 3);
    EXPECT_EQ(e.key(), "pressure.setpoint_mpa");
  }
}

TEST_F(ConfigFiles, MissingMainFileIsAnError) {
  EXPECT_THROW((void)load_config(dir_ / "nope.toml"), ConfigError);
}

TEST_F(ConfigFiles, ADirectoryOrAnUnreadableDropInIsNamed) {
  try {
    (void)load_config(dir_);
    FAIL() << "a directory was accepted as the configuration file";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("is a directory"), std::string::npos) << e.what();
  }
  write("weedspray.toml", "[pressure]\nsetpoint_mpa = 0.2\n");
  fs::create_directories(dir_ / "conf.d" / "50-folder.toml");  // a folder named like a drop-in
  try {
    (void)load_config(dir_ / "weedspray.toml");
    FAIL() << "a drop-in that is not a file was accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(e.file().find("50-folder.toml"), std::string::npos) << e.what();
  }
}

TEST(ConfigErrors, EveryGpioLineIsUsedOnceNamingBothKeys) {
  const auto twice = parse_error({{"m.toml", "[gpio]\nvalve_offsets = [1, 1, 2, 3]\n"}});
  EXPECT_EQ(twice.key(), "gpio.valve_offsets[1]");
  EXPECT_NE(std::string(twice.what())
                .find("m.toml:2: gpio.valve_offsets[1]: line 1 is already "
                      "gpio.valve_offsets[0]"),
            std::string::npos)
      << twice.what();
  const auto pump =
      parse_error({{"m.toml", "[gpio]\nvalve_offsets = [1, 2, 3, 4]\npump_offset = 1\n"}});
  EXPECT_EQ(pump.key(), "gpio.pump_offset");
  EXPECT_EQ(pump.line(), 3);
  EXPECT_NE(std::string(pump.what()).find("line 1 is already gpio.valve_offsets[0]"),
            std::string::npos);
  const auto input =
      parse_error({{"m.toml", "[gpio]\nvalve_offsets = [1, 2, 3, 4]\nwheel_offset = 2\n"}});
  EXPECT_EQ(input.key(), "gpio.wheel_offset");
  const auto names = parse_error(
      {{"m.toml", "[gpio]\nvalve_names = ['V0', 'V1', 'V2', 'V3']\nkey_name = 'V2'\n"}});
  EXPECT_EQ(names.key(), "gpio.key_name");
  const auto estop =
      parse_error({{"m.toml", "[gpio]\nvalve_offsets = [1, 2, 3, 4]\nestop_offset = 4\n"}});
  EXPECT_EQ(estop.key(), "gpio.estop_offset");
  EXPECT_EQ(parse("[gpio]\nvalve_offsets = [1, 2, 3, 4]\npump_offset = 5\nflow_offset = 6\n")
                .gpio.pump_offset,
            5);
}

// etc/weedspray.toml: the installed default. It must parse, equal the built-in defaults, and
// document every key (each key written out under its section with a comment above it).
TEST(DefaultConfigFile, ParsesAndDocumentsEveryKey) {
  const fs::path file = fs::path(WEEDSPRAY_SOURCE_DIR) / "etc" / "weedspray.toml";
  const Config config = load_config(file);
  const Config defaults = default_config();
  for (const auto& spec : config_keys()) {
    EXPECT_EQ(read_back(spec, const_cast<Config&>(config)),
              read_back(spec, const_cast<Config&>(defaults)))
        << spec.full_name() << " differs from its declared default";
  }
  std::ifstream in(file);
  std::string line;
  std::string section;
  std::string previous;
  std::set<std::string> documented;
  while (std::getline(in, line)) {
    if (line.starts_with("[[")) {
      section = line.substr(2, line.find("]]") - 2);
    } else if (line.starts_with("[")) {
      section = line.substr(1, line.find(']') - 1);
    } else if (const auto eq = line.find(" = "); eq != std::string::npos) {
      // A key that overrides the weed model's JSON is written commented out (unset).
      const bool commented = line.starts_with("# ");
      const std::string key =
          section + "." + line.substr(commented ? 2 : 0, eq - (commented ? 2 : 0));
      if (previous.starts_with("#") && (!commented || overrides_model_spec(key))) {
        documented.insert(key);
      }
    }
    previous = line;
  }
  for (const auto& spec : config_keys()) {
    EXPECT_TRUE(documented.count(spec.full_name())) << spec.full_name() << " not documented";
  }
  for (const auto& spec : camera_keys()) {
    EXPECT_TRUE(documented.count(spec.full_name())) << spec.full_name() << " not documented";
  }
}

// Ranges read as typed: "range 4096..2147483647", never "2.14748e+09" (6 significant digits).
TEST(DefaultConfigFile, RangesAreWrittenInFull) {
  const std::string text = documented_config();
  std::istringstream lines(text);
  int ranges = 0;
  for (std::string line; std::getline(lines, line);) {
    const auto at = line.find(", range ");
    if (at == std::string::npos) continue;
    ++ranges;
    const std::string range = line.substr(at, line.find(';', at) - at);
    EXPECT_EQ(range.find("e+"), std::string::npos) << line;
  }
  EXPECT_GT(ranges, 100);
  EXPECT_NE(text.find("range 4096..2147483647"), std::string::npos);
}

}  // namespace
}  // namespace weedspray::daemon
