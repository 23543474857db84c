#include "mpmcd/analysis/time_series.hpp"

#include <fmt/format.h>

#include <charconv>
#include <fstream>
#include <sstream>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::analysis {

namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::istringstream in(line);
  while (std::getline(in, field, ',')) {
    const auto b = field.find_first_not_of(" \t\r");
    const auto e = field.find_last_not_of(" \t\r");
    out.push_back(b == std::string::npos ? "" : field.substr(b, e - b + 1));
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

}  // namespace

bool TimeSeries::has(const std::string& name) const {
  for (const auto& n : names)
    if (n == name) return true;
  return false;
}

const std::vector<double>& TimeSeries::column(const std::string& name) const {
  for (std::size_t k = 0; k < names.size(); ++k)
    if (names[k] == name) return columns[k];
  throw InputError(path, 0, name, "missing column (is this a compaction run with four walls?)");
}

TimeSeries read_time_series(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot read the CSV time series: no such file");
  TimeSeries ts;
  ts.path = path;
  std::string line;
  std::int64_t lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (ts.names.empty()) {
      ts.names = split(line);
      ts.columns.resize(ts.names.size());
      continue;
    }
    const auto fields = split(line);
    if (fields.size() != ts.names.size())
      throw InputError(path, lineno, "",
                       fmt::format("expected {} fields (as in the header), got {}", ts.names.size(),
                                   fields.size()));
    for (std::size_t k = 0; k < fields.size(); ++k) {
      double v = 0;
      const char* b = fields[k].data();
      const char* e = b + fields[k].size();
      const auto [ptr, ec] = std::from_chars(b, e, v);
      if (ec != std::errc() || ptr != e)
        throw InputError(path, lineno, ts.names[k],
                         fmt::format("expected a number, got \"{}\"", fields[k]));
      ts.columns[k].push_back(v);
    }
  }
  if (ts.names.empty()) throw InputError(path, 0, "", "empty file: expected a CSV header");
  return ts;
}

}  // namespace mpmcd::analysis
