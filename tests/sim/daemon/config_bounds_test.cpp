// SPDX-License-Identifier: Apache-2.0
// What `weedsprayd --check-config` accepts, the daemon must be able to run: every numeric key
// of the schema at each end of its range, one at a time, through the loader; a configuration
// the loader accepts must then build the simulated machine's backends and the sprayer (every
// controller, schedule and detector the daemon constructs at start). A range in the schema
// wider than a constructor's own check fails here, naming the key and the value.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <sstream>
#include <string>

#include "daemon/backends/backends.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/sprayer/sprayer.hpp"

namespace weedspray::daemon {
namespace {

std::string toml_number(double value, KeyType type) {
  std::ostringstream out;
  if (type == KeyType::kInt) {
    out << static_cast<long long>(value);
  } else {
    out.precision(17);
    out << value;
    if (out.str().find_first_of(".e") == std::string::npos) out << ".0";
  }
  return out.str();
}

struct Tally {
  int tried = 0;
  int refused_by_loader = 0;
  int beyond_the_simulation = 0;
};

// One key at one value: loaded, then built as the daemon builds it at start.
void judge(const std::string& full_name, const std::string& text, Tally& tally) {
  ++tally.tried;
  Config config;
  try {
    config = load_config_from_strings({{"bounds.toml", text}});
  } catch (const ConfigError&) {
    ++tally.refused_by_loader;  // a rule between keys refuses it: --check-config says so too
    return;
  }
  Options options;
  options.sim = true;
  Backends backends;
  try {
    backends = make_sim_backends(config, options);
  } catch (const std::exception&) {
    ++tally.beyond_the_simulation;  // the plant model's own limits, not the daemon's
    return;
  }
  try {
    Sprayer sprayer(config, backends);
  } catch (const std::exception& error) {
    ADD_FAILURE() << full_name << ": the loader accepts\n"
                  << text << "but the daemon refuses it at start: " << error.what();
  }
}

// Each numeric key of `keys` at each end of its range, in a file with `table` as its header.
template <class Keys>
void try_range_ends(const Keys& keys, std::string_view table, Tally& tally) {
  for (const auto& spec : keys) {
    const KeyType type = spec.type();
    if (type != KeyType::kInt && type != KeyType::kDouble) continue;
    for (double value : {spec.min, spec.max}) {
      if (!std::isfinite(value)) continue;
      std::ostringstream text;
      if (table.empty()) {
        text << "[" << spec.section << "]";
      } else {
        text << table;
      }
      text << "\n" << spec.name << " = " << toml_number(value, type) << "\n";
      judge(spec.full_name(), text.str(), tally);
    }
  }
}

TEST(ConfigBounds, EveryValueTheLoaderAcceptsAtTheEndsOfItsRangeBuildsTheSprayer) {
  Tally tally;
  try_range_ends(config_keys(), "", tally);
  try_range_ends(camera_keys(), "[[camera]]", tally);
  std::cout << tally.tried << " values tried: " << tally.refused_by_loader
            << " refused by the loader, " << tally.beyond_the_simulation
            << " beyond the simulated machine\n";
  EXPECT_GT(tally.tried - tally.refused_by_loader - tally.beyond_the_simulation, 200);
}

}  // namespace
}  // namespace weedspray::daemon
