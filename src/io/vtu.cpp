#include "mpmcd/io/vtu.hpp"

#include <fmt/format.h>

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace mpmcd::io {

std::vector<double>& VtuPointCloud::add_array(const std::string& name, int components) {
  arrays_.push_back({name, components, std::vector<double>(n_ * components, 0.0)});
  return arrays_.back().values;
}

std::vector<std::int32_t>& VtuPointCloud::add_int_array(const std::string& name) {
  int_arrays_.push_back({name, std::vector<std::int32_t>(n_, 0)});
  return int_arrays_.back().values;
}

namespace {
// Raw appended block: UInt64 byte count followed by the bytes.
template <class T>
void append_block(std::string& blob, const T* data, std::size_t count) {
  const std::uint64_t bytes = count * sizeof(T);
  blob.append(reinterpret_cast<const char*>(&bytes), sizeof(bytes));
  blob.append(reinterpret_cast<const char*>(data), bytes);
}
}  // namespace

void VtuPointCloud::write(const std::string& path) const {
  std::string header;
  std::string blob;
  header += "<?xml version=\"1.0\"?>\n";
  header +=
      "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" "
      "header_type=\"UInt64\">\n<UnstructuredGrid>\n";
  header += fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n_, n_);
  header += "<PointData>\n";
  for (const auto& a : arrays_) {
    header += fmt::format(
        "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"{}\" format=\"appended\" "
        "offset=\"{}\"/>\n",
        a.name, a.components, blob.size());
    append_block(blob, a.values.data(), a.values.size());
  }
  for (const auto& a : int_arrays_) {
    header += fmt::format(
        "<DataArray type=\"Int32\" Name=\"{}\" NumberOfComponents=\"1\" format=\"appended\" "
        "offset=\"{}\"/>\n",
        a.name, blob.size());
    append_block(blob, a.values.data(), a.values.size());
  }
  header += "</PointData>\n<Points>\n";
  header += fmt::format(
      "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"{}\"/>\n",
      blob.size());
  append_block(blob, positions_.data(), positions_.size());
  header += "</Points>\n<Cells>\n";
  std::vector<std::int64_t> conn(n_), offsets(n_);
  std::vector<std::uint8_t> types(n_, 1);  // VTK_VERTEX
  for (std::size_t i = 0; i < n_; ++i) {
    conn[i] = static_cast<std::int64_t>(i);
    offsets[i] = static_cast<std::int64_t>(i + 1);
  }
  header += fmt::format(
      "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"{}\"/>\n",
      blob.size());
  append_block(blob, conn.data(), conn.size());
  header += fmt::format(
      "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"{}\"/>\n",
      blob.size());
  append_block(blob, offsets.data(), offsets.size());
  header +=
      fmt::format("<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"{}\"/>\n",
                  blob.size());
  append_block(blob, types.data(), types.size());
  header += "</Cells>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_";
  std::string text = header;
  text += blob;
  text += "\n</AppendedData>\n</VTKFile>\n";
  write_file_atomic(path, text);
}

void PvdSeries::add(double time, const std::string& relative_file) {
  entries_.emplace_back(time, relative_file);
  std::string text =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" "
      "byte_order=\"LittleEndian\">\n<Collection>\n";
  for (const auto& [t, f] : entries_)
    text +=
        fmt::format("<DataSet timestep=\"{:.17g}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t, f);
  text += "</Collection>\n</VTKFile>\n";
  write_file_atomic(path_, text);
}

void write_file_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  // POSIX calls, so that a failure names its reason (ENOSPC, EDQUOT, EFBIG, EIO...); the
  // partial .tmp is removed (docs/robustness.md).
  const auto fail = [&](const char* what, int err) {
    ::unlink(tmp.c_str());
    return std::runtime_error(fmt::format("cannot {} '{}': {}", what, tmp, std::strerror(err)));
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int err = errno;
    throw std::runtime_error(
        fmt::format("cannot open '{}' for writing: {}", tmp, std::strerror(err)));
  }
  std::size_t done = 0;
  while (done < text.size()) {
    const ::ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int err = n < 0 ? errno : EIO;
      ::close(fd);
      throw fail("write", err);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) throw fail("write", errno);  // e.g. a quota reached on a network FS
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    ::unlink(tmp.c_str());
    throw std::runtime_error(
        fmt::format("cannot rename '{}' to '{}': {}", tmp, path, ec.message()));
  }
}

}  // namespace mpmcd::io
