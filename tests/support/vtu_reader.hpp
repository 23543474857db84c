#pragma once
// Reads the point-cloud .vtu files mpmcd writes (raw appended binary, UInt64 block headers; the
// layout of io::VtuPointCloud, and of tools/vtu_points.py in Python) for the tests: the points and
// every named array as doubles.
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <stdexcept>
#include <string>
#include <vector>

namespace mpmcd::test_support {

struct VtuData {
  std::vector<double> points;                         // x, y, z per point [m]
  std::map<std::string, std::vector<double>> arrays;  // by name, components interleaved
};

inline VtuData read_vtu(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::string raw((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto start = raw.find("<AppendedData encoding=\"raw\">");
  if (start == std::string::npos) throw std::runtime_error(path + ": no raw appended data");
  const std::size_t blob = raw.find('_', start) + 1;
  const std::string header = raw.substr(0, start);
  VtuData out;
  const std::regex array(R"(<DataArray ([^>]*)/>)"), attr(R"((\w+)=\"([^\"]*)\")");
  for (auto it = std::sregex_iterator(header.begin(), header.end(), array);
       it != std::sregex_iterator(); ++it) {
    std::map<std::string, std::string> a;
    const std::string body = (*it)[1];
    for (auto k = std::sregex_iterator(body.begin(), body.end(), attr); k != std::sregex_iterator();
         ++k)
      a[(*k)[1]] = (*k)[2];
    const std::size_t off = blob + std::stoull(a.at("offset"));
    std::uint64_t bytes = 0;
    std::memcpy(&bytes, raw.data() + off, sizeof bytes);
    const char* data = raw.data() + off + sizeof bytes;
    std::vector<double> values;
    const std::string& type = a.at("type");
    const std::size_t size = type == "Float64" || type == "Int64" ? 8 : type == "Int32" ? 4 : 1;
    for (std::size_t i = 0; i < bytes / size; ++i) {
      const char* p = data + i * size;
      if (type == "Float64") {
        double v;
        std::memcpy(&v, p, 8);
        values.push_back(v);
      } else if (type == "Int64") {
        std::int64_t v;
        std::memcpy(&v, p, 8);
        values.push_back(static_cast<double>(v));
      } else if (type == "Int32") {
        std::int32_t v;
        std::memcpy(&v, p, 4);
        values.push_back(v);
      } else {
        values.push_back(static_cast<unsigned char>(*p));
      }
    }
    if (a.count("Name"))
      out.arrays[a["Name"]] = std::move(values);
    else
      out.points = std::move(values);
  }
  return out;
}

}  // namespace mpmcd::test_support
