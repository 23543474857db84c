#pragma once
/// VTK XML writers: point clouds as UnstructuredGrid (.vtu, raw appended binary), .pvd time series.
/// Files are written to "<path>.tmp" and renamed, so a crash never leaves a half-written file.
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

namespace mpmcd::io {

/// A cloud of vertices (VTK_VERTEX cells) with named point-data arrays, written as one .vtu file.
class VtuPointCloud {
 public:
  /// Creates an empty cloud of `n` points.
  explicit VtuPointCloud(std::size_t n) : n_(n), positions_(3 * n, 0.0) {}
  /// Number of points.
  std::size_t size() const { return n_; }
  /// Sets the position of point i [m]; missing components (2D) stay 0.
  void set_position(std::size_t i, double x, double y, double z = 0.0) {
    positions_[3 * i] = x;
    positions_[3 * i + 1] = y;
    positions_[3 * i + 2] = z;
  }
  /// Adds a point-data array of `components` doubles per point (1 scalar, 3 vector, 9 tensor).
  /// Returns the array storage (size n * components), valid for the cloud's lifetime.
  std::vector<double>& add_array(const std::string& name, int components);
  /// Adds a point-data array of 32-bit integers (1 component).
  std::vector<std::int32_t>& add_int_array(const std::string& name);
  /// Writes the file atomically; throws std::runtime_error on I/O failure.
  void write(const std::string& path) const;

 private:
  struct Array {
    std::string name;
    int components;
    std::vector<double> values;
  };
  struct IntArray {
    std::string name;
    std::vector<std::int32_t> values;
  };
  std::size_t n_;
  std::vector<double> positions_;
  std::deque<Array> arrays_;  // deque: references returned by add_array stay valid
  std::deque<IntArray> int_arrays_;
};

/// A ParaView .pvd collection listing one file per time [s]; rewritten atomically on each add.
class PvdSeries {
 public:
  /// `path`: the .pvd file; dataset file names are stored relative to its folder.
  explicit PvdSeries(std::string path) : path_(std::move(path)) {}
  /// Appends (time [s], file name relative to the .pvd) and rewrites the .pvd.
  void add(double time, const std::string& relative_file);
  /// Appends (time [s], file name) without rewriting the .pvd (rebuilding a series on restart).
  void restore(double time, const std::string& relative_file) {
    entries_.emplace_back(time, relative_file);
  }

 private:
  std::string path_;
  std::vector<std::pair<double, std::string>> entries_;
};

/// Writes `text` to `path` atomically (write "<path>.tmp", then rename); throws on failure.
void write_file_atomic(const std::string& path, const std::string& text);

}  // namespace mpmcd::io
