// SPDX-License-Identifier: Apache-2.0
// Figures over drawn machines (--plants): rows of named spreads. Text: a heading row (what,
// mean, sd, worst), "-- " lines before sections, then per spread its label and mean, sd and
// worst in the row's format. JSON: {"mean": ..., "sd": ..., "worst": ..., "n": N} per named
// row, the rows of a named section nested in an object of that name.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "lab/experiments/machines.hpp"
#include "lab/report/report.hpp"

namespace weedspray::lab {

Json spread_json(const lab::experiments::Spread& spread);

// A report over drawn machines: its JSON opens with "plants" and "seed".
Report fleet_report(int plants, std::uint64_t seed);

class SpreadTable {
 public:
  explicit SpreadTable(std::string heading);
  // A "-- text" line; the rows after it go into the JSON object `key` (empty: the top level).
  SpreadTable& section(std::string key, const std::string& text);
  // key empty: text only. text_format: one value, 12 wide, e.g. "%12.3f".
  SpreadTable& row(const std::string& key, const std::string& label,
                   const lab::experiments::Spread& spread, const std::string& text_format);
  // A text line `text` and, key not empty, the JSON member `key`: `value` in the section.
  SpreadTable& member(const std::string& key, Json value, const std::string& text);
  // A text line only (no row, no section).
  SpreadTable& note(const std::string& text);

  // The text lines; the JSON members into `report`'s object.
  void report_to(Report& report) const;

 private:
  struct JsonRow {
    std::string section;  // empty: the top level
    std::string key;
    Json value;
  };
  std::vector<std::string> lines_;
  std::vector<JsonRow> json_rows_;
  std::string section_;
};

}  // namespace weedspray::lab
