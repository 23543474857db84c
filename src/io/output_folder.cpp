// One output folder holds one run (docs/robustness.md, "Output folders").
#include "mpmcd/io/output_folder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "mpmcd/core/errors.hpp"

namespace mpmcd::io {

namespace fs = std::filesystem;

std::vector<std::string> files_in(const std::string& folder,
                                  const std::function<bool(const std::string&)>& belongs) {
  std::vector<std::string> out;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return out;
  for (const auto& e : fs::directory_iterator(folder, ec))
    if (!e.is_directory(ec) && belongs(e.path().filename().string()))
      out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  return out;
}

void claim_output_folder(const std::string& folder, const std::vector<std::string>& existing,
                         bool overwrite, const std::string& what, const std::string& source,
                         const std::string& key) {
  if (existing.empty()) return;
  if (overwrite) {
    for (const auto& f : existing) {
      std::error_code ec;
      fs::remove(f, ec);
      if (ec)
        throw std::runtime_error(
            fmt::format("--overwrite: cannot remove '{}': {}", f, ec.message()));
    }
    return;
  }
  std::string shown;
  for (std::size_t k = 0; k < existing.size() && k < 3; ++k)
    shown += (k ? ", " : "") + fs::path(existing[k]).filename().string();
  if (existing.size() > 3) shown += fmt::format(" and {} more", existing.size() - 3);
  throw InputError(source, 0, key,
                   fmt::format("a folder without the files of an earlier {}, but '{}' holds {}: "
                               "give --overwrite to remove them first, or choose another folder "
                               "(outputs of two runs are never mixed)",
                               what, folder, shown));
}

std::string regex_escape(const std::string& name) {
  std::string out;
  for (const char c : name) {
    if (std::string_view("\\^$.|?*+()[]{}").find(c) != std::string_view::npos) out += '\\';
    out += c;
  }
  return out;
}

}  // namespace mpmcd::io
