#include "mpmcd/app/run_folder.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <regex>
#include <vector>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/output_folder.hpp"

namespace mpmcd::app {

namespace fs = std::filesystem;

namespace {

// The folder of the checkpoint file `path`.
fs::path checkpoint_folder(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

// The files of the run named `name` in `folder` (docs/robustness.md, "Output folders"): the
// input copy and every output named after the run, with the .tmp files a crash may leave.
std::vector<std::string> run_files(const std::string& folder, const std::string& name) {
  const std::regex own("(input\\.toml|" + io::regex_escape(name) +
                       "(\\.csv|\\.pvd|_contacts\\.pvd|_[0-9]{6}\\.vtu|_contacts_[0-9]{6}\\.vtu|"
                       "_pairs_[0-9]{6}\\.csv|_grains_[0-9]{6}\\.csv|_forces_[0-9]{6}\\.csv|"
                       "_checkpoint_[0-9]{9}\\.h5|_last_good\\.vtu|"
                       "_timers\\.csv))(\\.tmp)?");
  return io::files_in(folder, [&](const std::string& f) { return std::regex_match(f, own); });
}

// The run name in an input copy (<folder>/input.toml) of an earlier run: [simulation] name, by
// default "mpmcd"; "" if the file cannot be read.
std::string earlier_run_name(const fs::path& input_copy) {
  std::ifstream in(input_copy);
  if (!in) return "";
  const std::regex table(R"re(\s*\[\s*([A-Za-z0-9_.]+)\s*\].*)re");
  const std::regex key(R"re(\s*name\s*=\s*"([A-Za-z0-9_.-]+)".*)re");
  std::string line, section, name = io::Config{}.simulation.name;
  std::smatch m;
  while (std::getline(in, line)) {
    if (std::regex_match(line, m, table))
      section = m[1];
    else if (section == "simulation" && std::regex_match(line, m, key))
      name = m[1];
  }
  return name;
}

// One folder, one run: a new run (or a restart written elsewhere than its checkpoint's folder)
// refuses a folder that holds input.toml or files of a run of this name, unless `overwrite`,
// which removes them, and those of the run named in the old input.toml, first. Rank 0 looks and
// tells the others.
void claim_run_folder(const io::Config& cfg, const RunOptions& opt, const std::string& dir,
                      const parallel::Comm& comm) {
  std::vector<char> verdict;
  if (comm.rank() == 0) {
    try {
      auto files = run_files(dir, cfg.simulation.name);
      const std::string earlier = earlier_run_name(fs::path(dir) / "input.toml");
      if (opt.overwrite && !earlier.empty() && earlier != cfg.simulation.name)
        for (auto& f : run_files(dir, earlier)) files.push_back(f);
      std::sort(files.begin(), files.end());
      files.erase(std::unique(files.begin(), files.end()), files.end());
      const std::string what =
          earlier.empty() || earlier == cfg.simulation.name
              ? fmt::format("run named '{}'", cfg.simulation.name)
              : fmt::format("run (named '{}', this one '{}')", earlier, cfg.simulation.name);
      io::claim_output_folder(dir, files, opt.overwrite, what,
                              opt.restart.empty() ? cfg.source_path : opt.restart,
                              opt.output_dir.empty() ? "output.folder" : "-o");
      if (opt.overwrite && !files.empty())
        log().info("--overwrite: removed {} files of the earlier run in {}", files.size(), dir);
    } catch (const InputError& e) {
      const std::string m = e.what();
      verdict.assign(m.begin(), m.end());
    }
  }
  if (comm.size() > 1) comm.broadcast(verdict, 0);
  if (!verdict.empty()) throw InputError(std::string(verdict.begin(), verdict.end()));
}

}  // namespace

std::string output_folder(const io::Config& cfg, const RunOptions& opt, bool restart) {
  if (restart && opt.output_dir.empty())  // continue where the checkpoint lies
    return checkpoint_folder(opt.restart).string();
  if (!opt.output_dir.empty()) return opt.output_dir;
  if (fs::path(cfg.output.folder).is_relative())
    return (fs::path(cfg.source_path).parent_path() / cfg.output.folder)
        .lexically_normal()
        .string();
  return cfg.output.folder;
}

std::string prepare_output_folder(const io::Config& cfg, const RunOptions& opt,
                                  const std::string& dir, bool restart,
                                  const parallel::Comm& comm) {
  std::error_code ec;
  const fs::path ckpt_dir = restart ? checkpoint_folder(opt.restart) : fs::path();
  const bool continuing = restart && fs::equivalent(ckpt_dir, dir, ec);
  if (!continuing) claim_run_folder(cfg, opt, dir, comm);
  return restart && !continuing ? ckpt_dir.string() : std::string();
}

}  // namespace mpmcd::app
