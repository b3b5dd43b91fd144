// Renders the key table as the commented default configuration file.
#include <toml++/toml.h>
#include <charconv>
#include <sstream>

#include "daemon/config/config_schema.hpp"

namespace weedspray::daemon {
namespace {

// Shortest text that reads back to the same double (3.3, not 3.2999999999999998), always with
// a '.' or exponent so TOML reads it as a float.
std::string format_double(double value) {
  char text[32];
  const auto end = std::to_chars(text, text + sizeof text, value).ptr;
  std::string number(text, end);
  if (number.find_first_of(".en") == std::string::npos) number += ".0";
  return number;
}

std::string format_value(const DefaultValue& value) {
  std::ostringstream out;
  std::visit(
      [&](const auto& v) {
        using V = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<V, std::vector<int>> ||
                      std::is_same_v<V, std::vector<std::string>>) {
          toml::array array;
          for (const auto& element : v) array.push_back(element);
          out << array;
        } else if constexpr (std::is_same_v<V, std::vector<double>>) {
          out << "[";
          for (std::size_t i = 0; i < v.size(); ++i) out << (i ? ", " : " ") << format_double(v[i]);
          out << (v.empty() ? "]" : " ]");
        } else if constexpr (std::is_same_v<V, int>) {
          out << toml::value<std::int64_t>(v);
        } else if constexpr (std::is_same_v<V, double>) {
          out << format_double(v);
        } else {
          out << toml::value<V>(v);
        }
      },
      value);
  return out.str();
}

template <class Root>
void document_key(std::ostringstream& out, const KeySpec<Root>& spec) {
  out << "# " << spec.doc << "\n# " << key_type_name(spec.type());
  if (!spec.unit.empty()) out << ", " << spec.unit;
  const auto type = spec.type();
  if (type == KeyType::kInt || type == KeyType::kDouble || type == KeyType::kIntList ||
      type == KeyType::kDoubleList) {
    out << ", range " << spec.min << ".." << spec.max;
  }
  if (!spec.choices.empty()) {
    out << ", one of";
    for (auto choice : spec.choices) out << " \"" << choice << "\"";
  }
  out << "; default " << format_value(spec.default_value) << "\n";
  if (is_safety_limit(spec.full_name()))
    out << "# safety limit: a reload keeps the running value; a restart applies a change\n";
  // A key that overrides the weed model's JSON is the model's own while unset.
  const char* unset = overrides_model_spec(spec.full_name()) ? "# " : "";
  out << unset << spec.name << " = " << format_value(spec.default_value) << "\n\n";
}

}  // namespace

std::string documented_config() {
  std::ostringstream out;
  out << "# weedspray configuration: /etc/weedspray/weedspray.toml\n"
         "# Drop-ins in /etc/weedspray/conf.d/*.toml are read after this file, in name order;\n"
         "# a key set in a later file wins. Unknown keys, wrong types and values out of range\n"
         "# are errors. Check a change with: weedsprayd --check-config [--config PATH]\n"
         "# then apply it with: sprayctl reload (or systemctl reload weedsprayd).\n"
         "# Every key below is at its default.\n";
  std::string_view section;
  for (const auto& spec : config_keys()) {
    if (spec.section != section) {
      section = spec.section;
      out << "\n[" << section << "]\n\n";
    }
    document_key(out, spec);
  }
  out << "# One [[camera]] table per camera; each steers a contiguous range of nozzles.\n"
         "# Without any [[camera]], one camera with these defaults steers every nozzle.\n"
         "[[camera]]\n\n";
  for (const auto& spec : camera_keys()) document_key(out, spec);
  return out.str();
}

}  // namespace weedspray::daemon
