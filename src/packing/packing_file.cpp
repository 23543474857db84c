// CSV packing files (docs/packing.md §6) and their VTU view.
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/vtu.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

namespace {

// Largest packing file read [bytes] (a 1e6-disk file is about 80 MB).
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t{512} << 20;

std::string_view trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const auto pos = s.find(sep, start);
    out.push_back(trim(s.substr(start, pos == std::string_view::npos ? pos : pos - start)));
    if (pos == std::string_view::npos) return out;
    start = pos + 1;
  }
}

// A shown field, shortened so that garbage does not flood the message.
std::string shown(std::string_view field) {
  std::string s(field.substr(0, 40));
  for (char& ch : s)
    if (static_cast<unsigned char>(ch) < 0x20 || static_cast<unsigned char>(ch) >= 0x7f) ch = '?';
  return field.size() > 40 ? "'" + s + "...'" : "'" + s + "'";
}

bool parse_double(std::string_view field, double& out) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return false;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), out);
  return ec == std::errc() && ptr == field.data() + field.size();
}

template <class Int>
bool parse_int(std::string_view field, Int& out) {
  if (!field.empty() && field.front() == '+') field.remove_prefix(1);
  if (field.empty()) return false;
  const auto [ptr, ec] = std::from_chars(field.data(), field.data() + field.size(), out);
  return ec == std::errc() && ptr == field.data() + field.size();
}

}  // namespace

void write_packing_csv(const Packing& packing, const std::string& path) {
  std::string text = "# mpmcd packing v1\n";
  if (packing.dimension == 3) {
    // 3D: the dimension line, a six-number box and a z column (2D files are unchanged).
    text += "# dimension = 3\n";
    text += fmt::format("# box = {:.17g} {:.17g} {:.17g} {:.17g} {:.17g} {:.17g}\n", packing.xmin,
                        packing.ymin, packing.zmin, packing.xmax, packing.ymax, packing.zmax);
  } else {
    text += fmt::format("# box = {:.17g} {:.17g} {:.17g} {:.17g}\n", packing.xmin, packing.ymin,
                        packing.xmax, packing.ymax);
  }
  text += fmt::format("# seed = {}\n", packing.seed);
  if (packing.periodic) text += "# boundary = periodic\n";
  if (packing.dimension == 3) {
    text += "id,x,y,z,radius\n";
    for (const auto& d : packing.disks)
      text += fmt::format("{},{:.17g},{:.17g},{:.17g},{:.17g}\n", d.id, d.x, d.y, d.z, d.radius);
  } else {
    text += "id,x,y,radius\n";
    for (const auto& d : packing.disks)
      text += fmt::format("{},{:.17g},{:.17g},{:.17g}\n", d.id, d.x, d.y, d.radius);
  }
  io::write_file_atomic(path, text);
}

Packing read_packing_csv(const std::string& path) {
  const auto fail = [&](std::int64_t line, const std::string& key, const std::string& what) {
    return InputError(path, line, key, what);
  };
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw fail(0, "", "a packing file (CSV), but it is a directory");
  const auto bytes = std::filesystem::file_size(path, ec);
  if (ec) throw fail(0, "", "cannot read the packing file: " + ec.message());
  if (bytes > kMaxFileBytes)
    throw fail(0, "",
               fmt::format("a packing file of at most {} bytes, got {}", kMaxFileBytes, bytes));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw fail(0, "", "cannot open the packing file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse_packing_csv(buffer.str(), path);
}

Packing parse_packing_csv(std::string_view text, const std::string& path) {
  const auto fail = [&](std::int64_t line, const std::string& key, const std::string& what) {
    return InputError(path, line, key, what);
  };
  Packing packing;
  bool has_box = false;
  std::int64_t box_line = 0, dimension_line = 0, header_line = 0;
  std::vector<double>
      box;            // the numbers of the '# box =' line, checked once the dimension is known
  int dimension = 0;  // from '# dimension =' (0: not given)
  std::vector<std::string> columns;
  int col_id = -1, col_x = -1, col_y = -1, col_z = -1, col_r = -1;
  std::vector<std::int64_t> row_line;
  std::unordered_map<std::int64_t, std::int64_t> id_line;
  std::int64_t line_no = 0, last_line = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    const auto end = text.find('\n', pos);
    std::string_view line(text.data() + pos, (end == std::string::npos ? text.size() : end) - pos);
    pos = end == std::string::npos ? text.size() : end + 1;
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    for (char ch : line) {
      const auto u = static_cast<unsigned char>(ch);
      if ((u < 0x20 && ch != '\t') || u == 0x7f)
        throw fail(line_no, "", "text (CSV) content, found a binary / control byte");
    }
    line = trim(line);
    if (line.empty()) continue;
    last_line = line_no;
    if (line.front() == '#') {
      // Header comments "# key = value": box, seed, boundary; other comments are ignored.
      const std::string_view body = trim(line.substr(1));
      const auto eq = body.find('=');
      if (eq == std::string_view::npos) continue;
      const std::string_view key = trim(body.substr(0, eq)), value = trim(body.substr(eq + 1));
      if (key == "box") {
        box.clear();
        bool numbers = true;
        for (auto v : split(value, ' ')) {
          if (v.empty()) continue;
          double b = 0.0;
          numbers = numbers && parse_double(v, b);
          box.push_back(b);
        }
        if (!numbers || (box.size() != 4 && box.size() != 6))
          throw fail(line_no, "box",
                     "'# box = xmin ymin xmax ymax' (four numbers; 3D: xmin ymin zmin xmax ymax "
                     "zmax) [m]");
        has_box = true;
        box_line = line_no;
      } else if (key == "dimension") {
        if (value != "2" && value != "3")
          throw fail(line_no, "dimension", "2 or 3, got " + shown(value));
        dimension = value == "3" ? 3 : 2;
        dimension_line = line_no;
      } else if (key == "seed") {
        if (!parse_int(value, packing.seed))
          throw fail(line_no, "seed", "an integer in [0, 2^64), got " + shown(value));
      } else if (key == "boundary") {
        if (value != "walls" && value != "periodic")
          throw fail(line_no, "boundary", "walls or periodic, got " + shown(value));
        packing.periodic = value == "periodic";
      }
      continue;
    }
    const auto fields = split(line, ',');
    if (columns.empty()) {
      // Column header: id, x, y, radius in any order; other columns are ignored.
      for (std::size_t c = 0; c < fields.size(); ++c) {
        const std::string name(fields[c]);
        for (const auto& known : columns)
          if (known == name) throw fail(line_no, name, "each column name once");
        columns.push_back(name);
        const int ci = static_cast<int>(c);
        if (name == "id") col_id = ci;
        if (name == "x") col_x = ci;
        if (name == "y") col_y = ci;
        if (name == "z") col_z = ci;
        if (name == "radius") col_r = ci;
      }
      header_line = line_no;
      // The dimension: the '# dimension =' line, else 3 when there is a z column.
      if (dimension == 0) dimension = col_z >= 0 ? 3 : 2;
      packing.dimension = dimension;
      if (dimension == 2 && (col_id < 0 || col_x < 0 || col_y < 0 || col_r < 0))
        throw fail(
            line_no, "",
            "the column header 'id,x,y,radius' (columns id, x, y, radius), got " + shown(line));
      if (dimension == 3 && (col_id < 0 || col_x < 0 || col_y < 0 || col_z < 0 || col_r < 0))
        throw fail(line_no, "",
                   fmt::format("the column header 'id,x,y,z,radius' of a 3D packing (columns id, "
                               "x, y, z, radius{}), got {}",
                               dimension_line > 0
                                   ? fmt::format("; '# dimension = 3' on line {}", dimension_line)
                                   : "",
                               shown(line)));
      continue;
    }
    if (fields.size() != columns.size())
      throw fail(line_no, "",
                 fmt::format("{} comma-separated fields as in the header, got {}", columns.size(),
                             fields.size()));
    if (static_cast<std::int64_t>(packing.disks.size()) >= kMaxDisks)
      throw fail(line_no, "", fmt::format("at most {} disks", kMaxDisks));
    Disk d;
    if (!parse_int(fields[col_id], d.id))
      throw fail(line_no, "id", "an integer, got " + shown(fields[col_id]));
    const std::pair<int, double*> reals[4] = {
        {col_x, &d.x}, {col_y, &d.y}, {col_r, &d.radius}, {dimension == 3 ? col_z : -1, &d.z}};
    for (const auto& [col, out] : reals) {
      if (col < 0) continue;  // z of a 2D packing
      const auto& name = columns[col];
      if (!parse_double(fields[col], *out))
        throw fail(line_no, name, "a number, got " + shown(fields[col]));
      if (!std::isfinite(*out))
        throw fail(line_no, name, "a finite number, got " + shown(fields[col]));
    }
    if (!(d.radius > 0.0))
      throw fail(line_no, "radius", fmt::format("a radius > 0 [m], got {}", d.radius));
    const auto [it, fresh] = id_line.emplace(d.id, line_no);
    if (!fresh)
      throw fail(line_no, "id",
                 fmt::format("unique ids, id {} already on line {}", d.id, it->second));
    packing.disks.push_back(d);
    row_line.push_back(line_no);
  }
  if (columns.empty())
    throw fail(line_no, "",
               "the column header 'id,x,y,radius' (the file has no data: empty or comments only)");
  if (packing.disks.empty()) throw fail(last_line, "", "at least one disk row after the header");

  const bool three = dimension == 3;
  if (has_box) {
    // The box has 2 x dimension numbers: lower corner, then upper corner.
    if (box.size() != static_cast<std::size_t>(2 * dimension))
      throw fail(box_line, "box",
                 three ? fmt::format("'# box = xmin ymin zmin xmax ymax zmax' (six numbers, the "
                                     "packing is 3D: line {}), got {}",
                                     dimension_line > 0 ? dimension_line : header_line, box.size())
                       : fmt::format("'# box = xmin ymin xmax ymax' (four numbers) [m], got {}",
                                     box.size()));
    bool ok = true;
    for (double b : box) ok = ok && std::isfinite(b);
    for (int a = 0; a < dimension; ++a) ok = ok && box[dimension + a] > box[a];
    if (!ok)
      throw fail(box_line, "box",
                 three ? "finite numbers with xmax > xmin, ymax > ymin and zmax > zmin"
                       : "finite numbers with xmax > xmin and ymax > ymin");
    packing.xmin = box[0];
    packing.ymin = box[1];
    packing.xmax = box[dimension];
    packing.ymax = box[dimension + 1];
    if (three) {
      packing.zmin = box[2];
      packing.zmax = box[5];
    }
  } else {
    if (packing.periodic)
      throw fail(0, "box", "a '# box = xmin ymin xmax ymax' line for a periodic packing");
    // Without a box: the bounding box of the disks.
    packing.xmin = packing.ymin = std::numeric_limits<double>::infinity();
    packing.xmax = packing.ymax = -std::numeric_limits<double>::infinity();
    packing.zmin = three ? std::numeric_limits<double>::infinity() : 0.0;
    packing.zmax = three ? -std::numeric_limits<double>::infinity() : 0.0;
    for (const auto& d : packing.disks) {
      packing.xmin = std::min(packing.xmin, d.x - d.radius);
      packing.ymin = std::min(packing.ymin, d.y - d.radius);
      packing.xmax = std::max(packing.xmax, d.x + d.radius);
      packing.ymax = std::max(packing.ymax, d.y + d.radius);
      if (three) {
        packing.zmin = std::min(packing.zmin, d.z - d.radius);
        packing.zmax = std::max(packing.zmax, d.z + d.radius);
      }
    }
  }
  // Disks must lie in the box: centers inside, and with walls no disk may cross a wall by more
  // than 1 % of its radius (DEM wall overlaps are far smaller).
  for (std::size_t i = 0; i < packing.disks.size(); ++i) {
    const auto& d = packing.disks[i];
    const bool center_in =
        d.x >= packing.xmin && d.x <= packing.xmax && d.y >= packing.ymin && d.y <= packing.ymax;
    const double slack = 0.99 * d.radius;
    const bool disk_in =
        packing.periodic || (d.x - slack >= packing.xmin && d.x + slack <= packing.xmax &&
                             d.y - slack >= packing.ymin && d.y + slack <= packing.ymax);
    if (!three && (!center_in || !disk_in))
      throw fail(row_line[i], "",
                 fmt::format("disk id {} (x = {:.6g}, y = {:.6g}, radius = {:.6g}) inside the box "
                             "[{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] of line {}: it is outside",
                             d.id, d.x, d.y, d.radius, packing.xmin, packing.xmax, packing.ymin,
                             packing.ymax, box_line));
    const bool z_in =
        d.z >= packing.zmin && d.z <= packing.zmax &&
        (packing.periodic || (d.z - slack >= packing.zmin && d.z + slack <= packing.zmax));
    if (three && (!center_in || !disk_in || !z_in))
      throw fail(
          row_line[i], "",
          fmt::format("sphere id {} (x = {:.6g}, y = {:.6g}, z = {:.6g}, radius = {:.6g}) "
                      "inside the box [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] x [{:.6g}, {:.6g}] "
                      "of line {}: it is outside",
                      d.id, d.x, d.y, d.z, d.radius, packing.xmin, packing.xmax, packing.ymin,
                      packing.ymax, packing.zmin, packing.zmax, box_line));
  }
  // Disks may touch but not overlap (a packing not relaxed, a duplicated row): the common area
  // would be counted twice in the volume and Phi of a run (docs/robustness.md).
  if (const auto o = find_grain_overlap(packing, kOverlapTolerance)) {
    const auto& a = packing.disks[o->first];
    const auto& b = packing.disks[o->second];
    const char* grain = three ? "sphere" : "disk";
    throw fail(row_line[o->second], "",
               fmt::format("{} id {} to overlap no other {} (touching is fine: up to {:g} of "
                           "the smaller diameter), but it overlaps {} id {} of line {} by "
                           "{:.6g} m = {:.3g} of the smaller diameter: a duplicated row or a "
                           "packing that is not relaxed",
                           grain, b.id, grain, kOverlapTolerance, grain, a.id, row_line[o->first],
                           o->depth, o->depth / o->size));
  }
  return packing;
}

void write_packing_vtu(const Packing& packing, const std::string& path) {
  const std::size_t n = packing.disks.size();
  io::VtuPointCloud cloud(n);
  // Each array is filled before the next is added: add_array may reallocate earlier storage.
  for (std::size_t i = 0; i < n; ++i)
    cloud.set_position(i, packing.disks[i].x, packing.disks[i].y, packing.disks[i].z);
  {
    auto& radius = cloud.add_array("radius", 1);
    for (std::size_t i = 0; i < n; ++i) radius[i] = packing.disks[i].radius;
  }
  {
    auto& diameter = cloud.add_array("diameter", 1);
    for (std::size_t i = 0; i < n; ++i) diameter[i] = 2.0 * packing.disks[i].radius;
  }
  bool ids_fit = true;
  for (const auto& d : packing.disks)
    ids_fit = ids_fit && d.id >= std::numeric_limits<std::int32_t>::min() &&
              d.id <= std::numeric_limits<std::int32_t>::max();
  if (ids_fit) {
    auto& id = cloud.add_int_array("id");
    for (std::size_t i = 0; i < n; ++i) id[i] = static_cast<std::int32_t>(packing.disks[i].id);
  } else {
    auto& id = cloud.add_array("id", 1);
    for (std::size_t i = 0; i < n; ++i) id[i] = static_cast<double>(packing.disks[i].id);
  }
  cloud.write(path);
}

}  // namespace mpmcd::packing
