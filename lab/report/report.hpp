// SPDX-License-Identifier: Apache-2.0
// The lab's table-driven reporter: a table of named fields (each with its heading, width and
// printf formats) prints both the human text and the --json object, so a report is a table of
// fields rather than hand-written printf lines. Numbers carry their own printf format in each
// form: the text and the JSON may show a figure with different precision. Lab-only: allocation
// and exceptions are fine here.
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace weedspray::lab {

// A JSON value whose numbers are rendered as they are added, with their printf format. dump()
// writes one line: {"key": value, ...} and [a, b], ", " and ": " as separators. A number that
// is not finite prints as printf prints it (nan, inf): the reports never produce one.
class Json {
 public:
  static Json number(double value, const char* format);  // format: e.g. "%.4f", "%g"
  static Json integer(long long value);
  static Json unsigned_integer(unsigned long long value);
  static Json boolean(bool value);
  static Json string(std::string_view value);  // escaped as JSON requires
  static Json object();
  static Json array();

  // Object: appends a member (members keep their order). Array: appends an element. Both
  // throw std::logic_error on the other kind.
  Json& add(std::string key, Json value);
  Json& push(Json value);
  // Object: appends every member of another object.
  Json& merge(const Json& object);

  bool is_object() const { return kind_ == Kind::kObject; }
  std::string dump() const;

 private:
  enum class Kind { kScalar, kObject, kArray };
  Json(Kind kind, std::string scalar) : kind_(kind), scalar_(std::move(scalar)) {}
  void write(std::string& out) const;

  Kind kind_;
  std::string scalar_;                                 // a scalar's JSON text
  std::vector<std::pair<std::string, Json>> members_;  // object members; array: empty keys
};

// One cell of a table row: a number, an integer, a flag, a text or (JSON only) a nested value;
// std::monostate: the row has no such field (left out of its JSON object, nothing in the text).
using Cell = std::variant<std::monostate, double, long long, bool, std::string, Json>;

// One named field of a table: how it heads and prints in the text, its name in the JSON.
struct Column {
  std::string key;        // JSON member name; empty: text only
  std::string heading;    // text heading, padded to heading_width
  int heading_width = 0;  // negative: left-aligned; 0 with no heading: spanned by the previous
  std::string
      text_format;  // printf format of a cell, e.g. "%8.3f", "%-10s", "%9d"; empty: JSON only
  std::string json_format;  // printf format of a number in the JSON, e.g. "%.4f"
  std::string gap = " ";    // text before the column's heading and cells (not the first's)
};

// Formats one cell with a printf format of one conversion: f/e/g for numbers, d/u for integers
// (any length modifier: the value is printed as long long), s for texts and flags (true/false).
// Throws std::logic_error when the format does not fit the cell.
std::string format_cell(const std::string& format, const Cell& cell);

// printf into a std::string.
std::string format_text(const char* format, ...) __attribute__((format(printf, 1, 2)));

// Rows of named fields. Text: the heading line, then one line per row. JSON: an array of the
// rows' objects, or, when every row is named, an object of them.
class Table {
 public:
  explicit Table(std::vector<Column> columns) : columns_(std::move(columns)) {}
  // One cell per column, in column order; throws std::invalid_argument otherwise.
  Table& row(std::vector<Cell> cells) { return row({}, std::move(cells)); }
  Table& row(std::string name, std::vector<Cell> cells);

  std::vector<std::string> text_lines(bool with_heading = true) const;
  Json json() const;

 private:
  std::string heading_line() const;

  std::vector<Column> columns_;
  std::vector<std::pair<std::string, std::vector<Cell>>> rows_;
};

// What a command reports: text lines and one JSON object, printed as one or the other.
class Report {
 public:
  Report() : json_(Json::object()) {}
  Json& json() { return json_; }
  // A text line (no newline).
  void line(const char* format, ...) __attribute__((format(printf, 2, 3)));
  void lines(const std::vector<std::string>& lines);
  // The table's text; its JSON as the member `key`, or, for named rows and no key, its rows
  // as members (unnamed rows and no key: text only).
  void table(const Table& table, const std::string& key = {});

  std::string text() const;
  // Stdout: the JSON on one line, or the text.
  void print(bool as_json) const;

 private:
  Json json_;
  std::vector<std::string> lines_;
};

}  // namespace weedspray::lab
