#pragma once
/// Reading the CSV time series written by `mpmcd run` (`<name>.csv`, docs/observables.md) as
/// named numeric columns.
#include <string>
#include <vector>

namespace mpmcd::analysis {

/// A numeric CSV table: a header of column names and one vector per column.
struct TimeSeries {
  std::string path;                          ///< file it was read from
  std::vector<std::string> names;            ///< column names, in file order
  std::vector<std::vector<double>> columns;  ///< values per column [units of the column]
  /// Number of data rows.
  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
  /// True if the table has column `name`.
  bool has(const std::string& name) const;
  /// The column `name`; throws InputError(path, 0, name, ...) if it is missing.
  const std::vector<double>& column(const std::string& name) const;
};

/// Reads a comma-separated file with a header line; every data field must be a number. Throws
/// InputError naming the file, line and column on a missing file, an empty file, a short row or
/// a field that is not a number.
TimeSeries read_time_series(const std::string& path);

}  // namespace mpmcd::analysis
