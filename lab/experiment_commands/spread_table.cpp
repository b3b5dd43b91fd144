// SPDX-License-Identifier: Apache-2.0
#include "lab/experiment_commands/spread_table.hpp"

namespace weedspray::lab {

Json spread_json(const lab::experiments::Spread& spread) {
  return Json::object()
      .add("mean", Json::number(spread.mean, "%.6g"))
      .add("sd", Json::number(spread.sd, "%.6g"))
      .add("worst", Json::number(spread.worst, "%.6g"))
      .add("n", Json::integer(spread.count));
}

Report fleet_report(int plants, std::uint64_t seed) {
  Report report;
  report.json().add("plants", Json::integer(plants)).add("seed", Json::unsigned_integer(seed));
  return report;
}

SpreadTable::SpreadTable(std::string heading) {
  lines_.push_back(format_text("%-34s%12s%12s%12s", heading.c_str(), "mean", "sd", "worst"));
}

SpreadTable& SpreadTable::section(std::string key, const std::string& text) {
  section_ = std::move(key);
  return note("-- " + text);
}

SpreadTable& SpreadTable::note(const std::string& text) {
  lines_.push_back(text);
  return *this;
}

SpreadTable& SpreadTable::row(const std::string& key, const std::string& label,
                              const lab::experiments::Spread& spread,
                              const std::string& text_format) {
  std::string line = format_text("%-34s", label.c_str());
  for (const double value : {spread.mean, spread.sd, spread.worst})
    line += format_cell(text_format, value);
  lines_.push_back(std::move(line));
  if (!key.empty()) json_rows_.push_back({section_, key, spread_json(spread)});
  return *this;
}

SpreadTable& SpreadTable::member(const std::string& key, Json value, const std::string& text) {
  lines_.push_back(text);
  if (!key.empty()) json_rows_.push_back({section_, key, std::move(value)});
  return *this;
}

void SpreadTable::report_to(Report& report) const {
  report.lines(lines_);
  for (std::size_t i = 0; i < json_rows_.size();) {
    const std::string& section = json_rows_[i].section;
    if (section.empty()) {
      report.json().add(json_rows_[i].key, json_rows_[i].value);
      ++i;
      continue;
    }
    Json object = Json::object();
    for (; i < json_rows_.size() && json_rows_[i].section == section; ++i)
      object.add(json_rows_[i].key, json_rows_[i].value);
    report.json().add(section, std::move(object));
  }
}

}  // namespace weedspray::lab
