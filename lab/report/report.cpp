// SPDX-License-Identifier: Apache-2.0
#include "lab/report/report.hpp"

#include <cctype>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>

namespace weedspray::lab {
namespace {

std::string vformat(const char* format, va_list args) {
  va_list copy;
  va_copy(copy, args);
  const int size = std::vsnprintf(nullptr, 0, format, copy);
  va_end(copy);
  if (size < 0) throw std::logic_error(std::string("bad printf format: ") + format);
  std::string out(static_cast<std::size_t>(size) + 1, '\0');
  std::vsnprintf(out.data(), out.size(), format, args);
  out.resize(static_cast<std::size_t>(size));
  return out;
}

// A printf format's one conversion: where it starts and ends, and its letter.
struct Conversion {
  std::size_t begin = 0;      // the '%'
  std::size_t modifiers = 0;  // the first length modifier (or the letter)
  std::size_t letter = 0;
};

Conversion one_conversion(const std::string& format) {
  std::optional<Conversion> found;
  for (std::size_t i = 0; i < format.size(); ++i) {
    if (format[i] != '%') continue;
    if (i + 1 < format.size() && format[i + 1] == '%') {
      ++i;
      continue;
    }
    if (found) throw std::logic_error("more than one conversion in format \"" + format + "\"");
    Conversion c{i, 0, 0};
    std::size_t j = i + 1;
    while (j < format.size() && std::strchr("-+ #0", format[j])) ++j;
    while (j < format.size() &&
           (std::isdigit(static_cast<unsigned char>(format[j])) || format[j] == '.'))
      ++j;
    c.modifiers = j;
    while (j < format.size() && std::strchr("hlLqjzt", format[j])) ++j;
    if (j == format.size()) throw std::logic_error("unfinished format \"" + format + "\"");
    c.letter = j;
    found = c;
    i = j;
  }
  if (!found) throw std::logic_error("no conversion in format \"" + format + "\"");
  return *found;
}

[[noreturn]] void mismatch(const std::string& format, const char* what) {
  throw std::logic_error("format \"" + format + "\" does not print " + what);
}

void write_escaped(std::string& out, std::string_view text) {
  out += '"';
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\r':
        out += "\\r";
        break;
      case '\t':
        out += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char code[8];
          std::snprintf(code, sizeof code, "\\u%04x", static_cast<unsigned>(c));
          out += code;
        } else {
          out += c;
        }
    }
  }
  out += '"';
}

}  // namespace

std::string format_text(const char* format, ...) {
  va_list args;
  va_start(args, format);
  std::string out = vformat(format, args);
  va_end(args);
  return out;
}

// ---------- Json ----------

Json Json::number(double value, const char* format) {
  const Conversion c = one_conversion(format);
  if (!std::strchr("fFeEgG", format[c.letter]) || c.modifiers != c.letter)
    mismatch(format, "a double");
  return {Kind::kScalar, format_text(format, value)};
}

Json Json::integer(long long value) {
  return {Kind::kScalar, format_text("%lld", value)};
}

Json Json::unsigned_integer(unsigned long long value) {
  return {Kind::kScalar, format_text("%llu", value)};
}

Json Json::boolean(bool value) {
  return {Kind::kScalar, value ? "true" : "false"};
}

Json Json::string(std::string_view value) {
  std::string out;
  write_escaped(out, value);
  return {Kind::kScalar, std::move(out)};
}

Json Json::object() {
  return {Kind::kObject, {}};
}
Json Json::array() {
  return {Kind::kArray, {}};
}

Json& Json::add(std::string key, Json value) {
  if (kind_ != Kind::kObject) throw std::logic_error("Json::add on a value that is no object");
  members_.emplace_back(std::move(key), std::move(value));
  return *this;
}

Json& Json::push(Json value) {
  if (kind_ != Kind::kArray) throw std::logic_error("Json::push on a value that is no array");
  members_.emplace_back(std::string{}, std::move(value));
  return *this;
}

Json& Json::merge(const Json& object) {
  if (object.kind_ != Kind::kObject)
    throw std::logic_error("Json::merge of a value that is no object");
  for (const auto& [key, value] : object.members_) add(key, value);
  return *this;
}

void Json::write(std::string& out) const {
  if (kind_ == Kind::kScalar) {
    out += scalar_;
    return;
  }
  out += kind_ == Kind::kObject ? '{' : '[';
  for (std::size_t i = 0; i < members_.size(); ++i) {
    if (i) out += ", ";
    if (kind_ == Kind::kObject) {
      write_escaped(out, members_[i].first);
      out += ": ";
    }
    members_[i].second.write(out);
  }
  out += kind_ == Kind::kObject ? '}' : ']';
}

std::string Json::dump() const {
  std::string out;
  write(out);
  return out;
}

// ---------- cells ----------

std::string format_cell(const std::string& format, const Cell& cell) {
  if (std::holds_alternative<std::monostate>(cell)) return {};
  const Conversion c = one_conversion(format);
  const char letter = format[c.letter];
  if (const auto* value = std::get_if<double>(&cell)) {
    if (!std::strchr("fFeEgG", letter) || c.modifiers != c.letter) mismatch(format, "a double");
    return format_text(format.c_str(), *value);
  }
  if (const auto* value = std::get_if<long long>(&cell)) {
    if (!std::strchr("diu", letter)) mismatch(format, "an integer");
    // Whatever length the format names (%zu, %d): the value goes in as long long.
    std::string as_long_long = format.substr(0, c.modifiers);
    as_long_long += "ll";
    as_long_long += format.substr(c.letter);
    return format_text(as_long_long.c_str(), *value);
  }
  if (c.modifiers != c.letter || letter != 's') mismatch(format, "a text");
  if (const auto* value = std::get_if<std::string>(&cell))
    return format_text(format.c_str(), value->c_str());
  if (const auto* value = std::get_if<bool>(&cell))
    return format_text(format.c_str(), *value ? "true" : "false");
  throw std::logic_error("a nested JSON value has no text form");
}

// ---------- Table ----------

Table& Table::row(std::string name, std::vector<Cell> cells) {
  if (cells.size() != columns_.size())
    throw std::invalid_argument(
        format_text("a table row of %zu cells for %zu columns", cells.size(), columns_.size()));
  rows_.emplace_back(std::move(name), std::move(cells));
  return *this;
}

std::string Table::heading_line() const {
  std::string out;
  bool first = true;
  for (const Column& column : columns_) {
    if (column.text_format.empty()) continue;
    const bool heads = !column.heading.empty() || column.heading_width != 0;
    if (heads) {
      if (!first) out += column.gap;
      out += format_text("%*s", column.heading_width, column.heading.c_str());
    }
    first = false;
  }
  return out;
}

std::vector<std::string> Table::text_lines(bool with_heading) const {
  std::vector<std::string> out;
  if (with_heading) out.push_back(heading_line());
  for (const auto& [name, cells] : rows_) {
    std::string line;
    bool first = true;
    for (std::size_t i = 0; i < columns_.size(); ++i) {
      const Column& column = columns_[i];
      if (column.text_format.empty()) continue;
      if (!first) line += column.gap;
      line += format_cell(column.text_format, cells[i]);
      first = false;
    }
    out.push_back(std::move(line));
  }
  return out;
}

Json Table::json() const {
  bool named = !rows_.empty();
  for (const auto& row : rows_) named = named && !row.first.empty();
  Json out = named ? Json::object() : Json::array();
  for (const auto& [name, cells] : rows_) {
    Json object = Json::object();
    for (std::size_t i = 0; i < columns_.size(); ++i) {
      const Column& column = columns_[i];
      const Cell& cell = cells[i];
      if (column.key.empty() || std::holds_alternative<std::monostate>(cell)) continue;
      if (const auto* value = std::get_if<double>(&cell)) {
        if (column.json_format.empty())
          throw std::logic_error("column " + column.key + " has no JSON format for a number");
        object.add(column.key, Json::number(*value, column.json_format.c_str()));
      } else if (const auto* value = std::get_if<long long>(&cell)) {
        object.add(column.key, Json::integer(*value));
      } else if (const auto* value = std::get_if<bool>(&cell)) {
        object.add(column.key, Json::boolean(*value));
      } else if (const auto* value = std::get_if<std::string>(&cell)) {
        object.add(column.key, Json::string(*value));
      } else {
        object.add(column.key, std::get<Json>(cell));
      }
    }
    if (named)
      out.add(name, std::move(object));
    else
      out.push(std::move(object));
  }
  return out;
}

// ---------- Report ----------

void Report::line(const char* format, ...) {
  va_list args;
  va_start(args, format);
  lines_.push_back(vformat(format, args));
  va_end(args);
}

void Report::lines(const std::vector<std::string>& lines) {
  lines_.insert(lines_.end(), lines.begin(), lines.end());
}

void Report::table(const Table& table, const std::string& key) {
  lines(table.text_lines());
  const Json rows = table.json();
  if (!key.empty())
    json_.add(key, rows);
  else if (rows.is_object())
    json_.merge(rows);
}

std::string Report::text() const {
  std::string out;
  for (const std::string& line : lines_) {
    out += line;
    out += '\n';
  }
  return out;
}

void Report::print(bool as_json) const {
  const std::string out = as_json ? json_.dump() + "\n" : text();
  std::fwrite(out.data(), 1, out.size(), stdout);
}

}  // namespace weedspray::lab
