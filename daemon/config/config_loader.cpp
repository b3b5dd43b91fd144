// SPDX-License-Identifier: Apache-2.0
// Parses TOML documents into Config against the key table of config_schema.cpp.
#include <toml++/toml.h>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <type_traits>

#include "daemon/config/config.hpp"
#include "daemon/config/config_loader.hpp"
#include "daemon/config/config_rules.hpp"
#include "daemon/config/config_schema.hpp"
#include "daemon/config/target_rate.hpp"

namespace weedspray::daemon {

namespace {

std::string_view node_type_name(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table:
      return "table";
    case toml::node_type::array:
      return "array";
    case toml::node_type::string:
      return "string";
    case toml::node_type::integer:
      return "integer";
    case toml::node_type::floating_point:
      return "floating-point number";
    case toml::node_type::boolean:
      return "boolean";
    default:
      return "date/time";
  }
}

// An integer or floating-point node's value.
double number_of(const toml::node& node) {
  return node.is_integer() ? static_cast<double>(node.as_integer()->get())
                           : node.as_floating_point()->get();
}

int line_of(const toml::node& node) {
  return static_cast<int>(node.source().begin.line);
}

template <class Root>
void apply_default(const KeySpec<Root>& spec, Root& root) {
  std::visit(
      [&](auto access) {
        auto& member = access(root);
        using Member = std::remove_reference_t<decltype(member)>;
        member = std::get<Member>(spec.default_value);
      },
      spec.field);
}

struct Where {
  const std::string& file;
  const std::string& key;  // full key name as written ("camera[1].fps")
};

template <class Root>
void set_from_node(const KeySpec<Root>& spec, Root& root, const toml::node& node,
                   const Where& where) {
  const auto fail = [&](const std::string& message) {
    throw ConfigError(where.file, line_of(node), where.key, message);
  };
  const auto expect = [&](std::string_view wanted) {
    fail("expected " + std::string(wanted) + ", got " + std::string(node_type_name(node)));
  };
  const auto check_range = [&](double value) {
    if (!std::isfinite(value) || value < spec.min || value > spec.max) {
      fail(format_number(value) + " is outside " + format_number(spec.min) + ".." +
           format_number(spec.max) + (spec.unit.empty() ? "" : " " + std::string(spec.unit)));
    }
  };
  // An array key: every element must pass `accepts`; `convert` reads (and range-checks) it.
  const auto set_list = [&]<class T>(std::type_identity<T>, const std::string& wanted,
                                     bool (toml::node::*accepts)() const noexcept, auto convert) {
    if (!node.is_array()) expect("array of " + wanted);
    std::vector<T> values;
    for (const auto& element : *node.as_array()) {
      if (!(element.*accepts)()) {
        throw ConfigError(
            where.file, line_of(element), where.key,
            "expected " + wanted + " in the array, got " + std::string(node_type_name(element)));
      }
      values.push_back(convert(element));
    }
    std::get<std::vector<T>& (*)(Root&)>(spec.field)(root) = std::move(values);
  };
  switch (spec.type()) {
    case KeyType::kBool:
      if (!node.is_boolean()) expect("boolean");
      std::get<bool& (*)(Root&)>(spec.field)(root) = node.as_boolean()->get();
      break;
    case KeyType::kInt: {
      if (!node.is_integer()) expect("integer");
      const auto value = node.as_integer()->get();
      check_range(static_cast<double>(value));
      std::get<int& (*)(Root&)>(spec.field)(root) = static_cast<int>(value);
      break;
    }
    case KeyType::kDouble: {
      if (!node.is_number()) expect("number");
      const double value = number_of(node);
      check_range(value);
      std::get<double& (*)(Root&)>(spec.field)(root) = value;
      break;
    }
    case KeyType::kString:
    case KeyType::kEnum: {
      if (!node.is_string()) expect("string");
      const std::string& value = node.as_string()->get();
      if (!spec.choices.empty() &&
          std::find(spec.choices.begin(), spec.choices.end(), value) == spec.choices.end()) {
        std::string allowed;
        for (auto choice : spec.choices) {
          allowed += (allowed.empty() ? "" : ", ") + std::string("\"") + std::string(choice) + "\"";
        }
        fail("\"" + value + "\" is not one of " + allowed);
      }
      std::get<std::string& (*)(Root&)>(spec.field)(root) = value;
      break;
    }
    case KeyType::kIntList:
      set_list(std::type_identity<int>{}, "integers", &toml::node::is_integer,
               [&](const toml::node& element) {
                 const auto value = element.as_integer()->get();
                 check_range(static_cast<double>(value));
                 return static_cast<int>(value);
               });
      break;
    case KeyType::kDoubleList:
      set_list(std::type_identity<double>{}, "numbers", &toml::node::is_number,
               [&](const toml::node& element) {
                 const double value = number_of(element);
                 check_range(value);
                 return value;
               });
      break;
    case KeyType::kStringList:
      set_list(std::type_identity<std::string>{}, "strings", &toml::node::is_string,
               [](const toml::node& element) { return element.as_string()->get(); });
      break;
  }
}

template <class Root>
std::map<std::string, const KeySpec<Root>*, std::less<>> index_by_name(
    const std::vector<KeySpec<Root>>& specs) {
  std::map<std::string, const KeySpec<Root>*, std::less<>> index;
  for (const auto& spec : specs) index[spec.full_name()] = &spec;
  return index;
}

class Loader {
 public:
  Loader() : config_(default_config()) {}

  void apply(const std::string& file, const toml::table& document) {
    config_.files.push_back(file);
    for (const auto& [section_key, section_node] : document) {
      const std::string section(section_key.str());
      const int line = static_cast<int>(section_key.source().begin.line);
      if (section == "camera") {
        apply_cameras(file, section_node);
        continue;
      }
      if (!sections().count(section)) {
        note(ConfigError(file, line, section, "unknown section"));
        continue;
      }
      if (!section_node.is_table()) {
        note(ConfigError(file, line, section, "expected a [" + section + "] table"));
        continue;
      }
      for (const auto& [name_key, value_node] : *section_node.as_table()) {
        const std::string full = section + "." + std::string(name_key.str());
        set_key(keys_, full, config_, file, full, name_key, value_node);
      }
    }
  }

  // A problem of one key or file: the loader goes on, so that every such problem is reported
  // at once (finish() throws them all).
  void note(const ConfigError& error) { errors_.push_back(error); }
  // The key `name` of `index` set in `root` from `value_node` (written as `full`), its source
  // recorded; an unknown key or a bad value is noted instead.
  template <class Index, class Root>
  void set_key(const Index& index, const std::string& name, Root& root, const std::string& file,
               const std::string& full, const toml::key& name_key, const toml::node& value_node) {
    const auto found = index.find(name);
    if (found == index.end()) {
      note(ConfigError(file, static_cast<int>(name_key.source().begin.line), full, "unknown key"));
      return;
    }
    try {
      set_from_node(*found->second, root, value_node, Where{file, full});
    } catch (const ConfigError& error) {
      note(error);
      return;
    }
    config_.sources[full] = KeySource{file, line_of(value_node)};
  }

  // One file's problems in the order of its lines (the TOML tables come sorted by name).
  void end_of_file() {
    std::stable_sort(
        errors_.begin() + static_cast<std::ptrdiff_t>(errors_in_earlier_files_), errors_.end(),
        [](const ConfigError& a, const ConfigError& b) { return a.line() < b.line(); });
    errors_in_earlier_files_ = errors_.size();
  }

  Config finish(WeedSourceCheck check) {
    // Rules between keys judge values that all parsed; until then they would only add noise.
    if (!errors_.empty()) throw ConfigError::listing(errors_);
    if (!cameras_given_) config_.cameras.front().nozzle_count = config_.boom.nozzles;
    apply_target_rate();
    validate();
    if (check != nullptr) {
      try {
        config_.model = check(config_);
      } catch (const VisionKeyError& error) {
        // A key left at its default is reported where the weed source was chosen.
        fail(error.key(), error.what(), "vision.weed_source");
      }
    }
    return std::move(config_);
  }

 private:
  static const std::set<std::string>& sections() {
    static const std::set<std::string> names = [] {
      std::set<std::string> result;
      for (const auto& spec : config_keys()) result.emplace(spec.section);
      return result;
    }();
    return names;
  }

  void apply_cameras(const std::string& file, const toml::node& node) {
    const auto* array = node.as_array();
    if (array == nullptr || !array->is_array_of_tables() || array->empty()) {
      throw ConfigError(file, line_of(node), "camera",
                        "cameras are declared as [[camera]] tables, one per camera");
    }
    cameras_given_ = true;
    config_.cameras.clear();  // a file that declares cameras declares all of them
    std::erase_if(config_.sources,
                  [](const auto& entry) { return entry.first.starts_with("camera["); });
    for (std::size_t i = 0; i < array->size(); ++i) {
      CameraSection camera{};
      for (const auto& spec : camera_keys()) apply_default(spec, camera);
      config_.sources["camera[" + std::to_string(i) + "]"] =
          KeySource{file, line_of(*array->get(i))};
      for (const auto& [name_key, value_node] : *array->get(i)->as_table()) {
        const std::string name(name_key.str());
        const std::string full = "camera[" + std::to_string(i) + "]." + name;
        set_key(camera_index_, "camera." + name, camera, file, full, name_key, value_node);
      }
      config_.cameras.push_back(std::move(camera));
    }
  }

  [[noreturn]] void fail(const std::string& key, const std::string& message,
                         const std::string& located_by = "") const {
    fail_at_key(config_, key, message, located_by);
  }

  void validate() const { check_config_rules(config_); }

  void apply_target_rate() {
    const std::string error = apply_target_rate_l_per_ha(config_);
    if (!error.empty()) fail("spray.target_rate_l_per_ha", error);
  }

  Config config_;
  bool cameras_given_ = false;
  std::vector<ConfigError> errors_;
  std::size_t errors_in_earlier_files_ = 0;
  std::map<std::string, const KeySpec<Config>*, std::less<>> keys_ = index_by_name(config_keys());
  std::map<std::string, const KeySpec<CameraSection>*, std::less<>> camera_index_ =
      index_by_name(camera_keys());
};

toml::table parse_document(std::string_view text, const std::string& name) {
  try {
    return toml::parse(text, std::string_view(name));
  } catch (const toml::parse_error& error) {
    throw ConfigError(name, static_cast<int>(error.source().begin.line), "",
                      std::string(error.description()));
  }
}

std::string read_file(const std::filesystem::path& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (error || !std::filesystem::exists(status)) {
    throw ConfigError(path.string(), 0, "", "cannot be read: no such file");
  }
  if (!std::filesystem::is_regular_file(status)) {
    throw ConfigError(path.string(), 0, "",
                      std::filesystem::is_directory(status)
                          ? "is a directory, not a configuration file"
                          : "is not a regular file");
  }
  // A configuration is a few tens of kB; a file far larger is a mistake (a log or an image
  // saved under the wrong name), and parsing it would stall the reload for seconds.
  const auto size = std::filesystem::file_size(path, error);
  if (!error && size > kMaxConfigFileBytes) {
    throw ConfigError(path.string(), 0, "",
                      std::to_string(size) + " bytes: a configuration file has at most " +
                          std::to_string(kMaxConfigFileBytes) + " bytes");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), 0, "", "cannot be read (permission?)");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

Config default_config() {
  Config config{};
  for (const auto& spec : config_keys()) apply_default(spec, config);
  CameraSection camera{};
  for (const auto& spec : camera_keys()) apply_default(spec, camera);
  config.cameras.push_back(std::move(camera));
  return config;
}

Config load_config_documents(const std::vector<std::pair<std::string, std::string>>& documents,
                             WeedSourceCheck check) {
  Loader loader;
  for (const auto& [name, text] : documents) {
    try {
      loader.apply(name, parse_document(text, name));
    } catch (const ConfigError& error) {
      loader.note(error);  // a file that does not parse: the others are still read
    }
    loader.end_of_file();
  }
  return loader.finish(check);
}

Config load_config_without_vision(const std::filesystem::path& main_file) {
  return load_config_files(main_file, nullptr);
}

Config load_config_files(const std::filesystem::path& main_file, WeedSourceCheck check) {
  std::vector<std::pair<std::string, std::string>> documents;
  documents.emplace_back(main_file.string(), read_file(main_file));
  const auto drop_in_dir = main_file.parent_path() / "conf.d";
  std::error_code error;
  if (std::filesystem::is_directory(drop_in_dir, error)) {
    std::vector<std::filesystem::path> drop_ins;
    // Listing errors are ConfigErrors naming the folder (directory_iterator would throw a
    // filesystem_error out of a reload).
    std::filesystem::directory_iterator entries(drop_in_dir, error);
    if (error) {
      throw ConfigError(drop_in_dir.string(), 0, "", "cannot be listed: " + error.message());
    }
    for (auto it = entries; it != std::filesystem::directory_iterator(); it.increment(error)) {
      if (error) {
        throw ConfigError(drop_in_dir.string(), 0, "", "cannot be listed: " + error.message());
      }
      if (it->path().extension() == ".toml") drop_ins.push_back(it->path());
    }
    std::sort(drop_ins.begin(), drop_ins.end());
    for (const auto& path : drop_ins) documents.emplace_back(path.string(), read_file(path));
  }
  return load_config_documents(documents, check);
}

}  // namespace weedspray::daemon
