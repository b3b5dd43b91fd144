// SPDX-License-Identifier: Apache-2.0
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

// A range bound as a reader types it: 16777216, 1000000 or 0.35, not 1.67772e+07.
std::string bound_text(double bound) {
  std::ostringstream out;
  out.precision(15);
  out << bound;
  return out.str();
}

// "number, MPa, range 0..2; default 0.3": type, unit, range, choices and default of a key.
template <class Root>
std::string key_summary(const KeySpec<Root>& spec) {
  std::ostringstream out;
  out << key_type_name(spec.type());
  if (!spec.unit.empty()) out << ", " << spec.unit;
  const auto type = spec.type();
  if (type == KeyType::kInt || type == KeyType::kDouble || type == KeyType::kIntList ||
      type == KeyType::kDoubleList) {
    out << ", range " << bound_text(spec.min) << ".." << bound_text(spec.max);
  }
  if (!spec.choices.empty()) {
    out << ", one of";
    for (auto choice : spec.choices) out << " \"" << choice << "\"";
  }
  out << "; default " << format_value(spec.default_value);
  return out.str();
}

template <class Root>
void document_key(std::ostringstream& out, const KeySpec<Root>& spec) {
  out << "# " << spec.doc << "\n# " << key_summary(spec) << "\n";
  if (is_safety_limit(spec.full_name()))
    out << "# safety limit: a reload keeps the running value; a restart applies a change\n";
  // A key that overrides the weed model's JSON is the model's own while unset.
  const char* unset = overrides_model_spec(spec.full_name()) ? "# " : "";
  out << unset << spec.name << " = " << format_value(spec.default_value) << "\n\n";
}

// Text as roff reads it literally: backslashes escaped, hyphens as ASCII hyphen-minus (so
// option and key names can be searched and copied), no line starting with a control character.
std::string roff_text(std::string_view text) {
  std::string out;
  bool line_start = true;
  for (const char c : text) {
    if (line_start && (c == '.' || c == '\'')) out += "\\&";
    if (c == '\\') {
      out += "\\e";
    } else if (c == '-') {
      out += "\\-";
    } else {
      out += c;
    }
    line_start = c == '\n';
  }
  return out;
}

template <class Root>
void man_key(std::ostringstream& out, const KeySpec<Root>& spec) {
  out << ".TP\n.B " << roff_text(spec.name) << "\n"
      << roff_text(spec.doc) << "\n.br\n"
      << roff_text(key_summary(spec)) << "\n";
  if (is_safety_limit(spec.full_name())) {
    out << ".br\nSafety limit: a reload keeps the running value; a restart applies a change.\n";
  }
}

}  // namespace

std::string config_reference_man(std::string_view version) {
  std::ostringstream out;
  out << ".TH WEEDSPRAY.TOML 5 \"\" \"weedspray " << roff_text(version)
      << "\" \"File Formats Manual\"\n"
         ".SH NAME\n"
         "weedspray.toml \\- configuration of the weedsprayd sprayer controller\n"
         ".SH SYNOPSIS\n"
         ".B /etc/weedspray/weedspray.toml\n"
         ".br\n"
         ".B /etc/weedspray/conf.d/*.toml\n"
         ".SH DESCRIPTION\n"
         ".BR weedsprayd (8)\n"
         "reads its configuration, in TOML, from\n"
         ".I /etc/weedspray/weedspray.toml\n"
         "(or the file given with\n"
         ".BR \\-\\-config ),\n"
         "then the drop\\-ins\n"
         ".I conf.d/*.toml\n"
         "beside it in name order; a key set in a later file wins.\n"
         "Unknown keys, wrong types and values out of range are errors.\n"
         ".PP\n"
         "Check a change with\n"
         ".B weedsprayd \\-\\-check\\-config\n"
         "and apply it with\n"
         ".B sprayctl reload\n"
         "(or\n"
         ".BR \"systemctl reload weedsprayd\" ).\n"
         ".B weedsprayd \\-\\-print\\-default\\-config\n"
         "prints every key below, documented, at its default.\n"
         ".PP\n"
         "Each key below gives its meaning, then its type, unit, allowed range or values and its\n"
         "default.\n";
  std::string_view section;
  for (const auto& spec : config_keys()) {
    if (spec.section != section) {
      section = spec.section;
      out << ".SH [" << roff_text(section) << "]\n";
    }
    man_key(out, spec);
  }
  out << ".SH [[camera]]\n"
         "One [[camera]] table per camera; each steers a contiguous range of nozzles.\n"
         "Without any [[camera]], one camera with the defaults steers every nozzle.\n";
  for (const auto& spec : camera_keys()) man_key(out, spec);
  out << ".SH FILES\n"
         ".TP\n.I /etc/weedspray/weedspray.toml\n"
         "the main configuration file, every key at its default as shipped\n"
         ".TP\n.I /etc/weedspray/conf.d/*.toml\n"
         "drop\\-ins, read after the main file in name order\n"
         ".SH SEE ALSO\n"
         ".BR weedsprayd (8),\n"
         ".BR sprayctl (1)\n";
  return out.str();
}

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
