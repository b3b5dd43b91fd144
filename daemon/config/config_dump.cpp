// SPDX-License-Identifier: Apache-2.0
// --dump-config: the configuration in force as one TOML document with every key, which the
// loader reads back to the same configuration.
#include <toml++/toml.h>

#include <sstream>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/config_schema.hpp"

namespace weedspray::daemon {

namespace {

template <class Root>
void insert_value(toml::table& table, const KeySpec<Root>& spec, Root& root) {
  std::visit(
      [&](auto access) {
        const auto& value = access(root);
        using Value = std::remove_cvref_t<decltype(value)>;
        if constexpr (std::is_same_v<Value, std::vector<int>> ||
                      std::is_same_v<Value, std::vector<std::string>> ||
                      std::is_same_v<Value, std::vector<double>>) {
          toml::array array;
          for (const auto& element : value) array.push_back(element);
          table.insert_or_assign(spec.name, std::move(array));
        } else {
          table.insert_or_assign(spec.name, value);
        }
      },
      spec.field);
}

}  // namespace

std::string dump_config(const Config& config) {
  Config copy = config;  // accessors take non-const references
  toml::table root;
  for (const auto& spec : config_keys()) {
    auto* section = root[spec.section].as_table();
    if (section == nullptr) {
      root.insert_or_assign(spec.section, toml::table{});
      section = root[spec.section].as_table();
    }
    insert_value(*section, spec, copy);
  }
  toml::array cameras;
  for (auto& camera : copy.cameras) {
    toml::table table;
    for (const auto& spec : camera_keys()) insert_value(table, spec, camera);
    cameras.push_back(std::move(table));
  }
  root.insert_or_assign("camera", std::move(cameras));
  std::ostringstream out;
  out << root << "\n";
  return out.str();
}

}  // namespace weedspray::daemon
