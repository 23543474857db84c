#pragma once
/// One output folder holds one run (docs/robustness.md, "Output folders"): `run`, `pack` and
/// `analyze` refuse a folder that already holds files of an earlier output of theirs, unless
/// --overwrite is given, in which case those files are removed first.
#include <functional>
#include <string>
#include <vector>

namespace mpmcd::io {

/// The files directly in `folder` whose file name `belongs` accepts, sorted; none if the folder
/// does not exist [paths].
std::vector<std::string> files_in(const std::string& folder,
                                  const std::function<bool(const std::string&)>& belongs);

/// Makes `folder` ready for a new output whose earlier files are `existing` (from files_in):
/// none, nothing to do; otherwise with `overwrite` they are removed, without it InputError (exit
/// 2) naming `source` (the input), `key` (where the folder was chosen), the folder, up to three
/// of the files and `what` (e.g. "run 'case'").
void claim_output_folder(const std::string& folder, const std::vector<std::string>& existing,
                         bool overwrite, const std::string& what, const std::string& source,
                         const std::string& key);

/// `name` with the characters special to std::regex (ECMAScript) escaped.
std::string regex_escape(const std::string& name);

}  // namespace mpmcd::io
