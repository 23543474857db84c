// The `mpmcd pack <input>` command (docs/packing.md §9).
#include "mpmcd/packing/pack_command.hpp"

#include <fmt/format.h>

#include <filesystem>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/core/log.hpp"
#include "mpmcd/io/output_folder.hpp"
#include "mpmcd/packing/input.hpp"
#include "mpmcd/packing/overlap.hpp"
#include "mpmcd/packing/packing.hpp"

namespace mpmcd::packing {

int pack_command(const std::string& input_path, bool quiet, bool overwrite) {
  if (quiet) setup_logging(Verbosity::kQuiet);
  const PackingInput input = load_packing_input(input_path);
  // One folder, one packing of this name (docs/robustness.md, "Output folders"): checked before
  // the DEM runs, the files removed (--overwrite) only once the new packing is known to relax.
  const auto earlier = io::files_in(input.output_folder, [&](const std::string& f) {
    for (const char* ext : {".csv", ".vtu", ".csv.tmp", ".vtu.tmp"})
      if (f == input.output_name + ext) return true;
    return false;
  });
  const std::string what = fmt::format("packing named '{}'", input.output_name);
  if (!overwrite)
    io::claim_output_folder(input.output_folder, earlier, false, what, input_path, "output.folder");
  PackingReport report;
  Packing packing;
  try {
    packing = generate_packing(input.params, report);
  } catch (const InputError& e) {
    // Parameter conflicts found while generating (e.g. a box too small): name the input file.
    // The message reads "input: key 'K': expectation" (core/errors.cpp).
    const std::string msg = e.what(), mark = "key '" + e.key() + "': ";
    const auto at = msg.find(mark);
    throw InputError(input_path, 0, e.key(),
                     at == std::string::npos ? msg : msg.substr(at + mark.size()));
  }
  // A packing `mpmcd run` would refuse (overlapping disks, docs/robustness.md) is not written:
  // exit 3, as a simulation that cannot go on.
  if (const auto o = find_grain_overlap(packing, kOverlapTolerance)) {
    const char* grains = packing.dimension == 3 ? "spheres" : "disks";
    fmt::print(stderr,
               "mpmcd pack: {}: the packing did not relax: {} {} and {} overlap by {:.3g} of "
               "the smaller diameter (mpmcd run accepts up to {:g}; largest overlap {:.3g} "
               "d_mean after {} DEM steps, phi = {:.4f}). Nothing written. Lower target_phi or "
               "friction (frictional {} jam at a lower phi), or raise max_relax_steps.\n",
               input_path, grains, packing.disks[o->first].id, packing.disks[o->second].id,
               o->depth / o->size, kOverlapTolerance, report.max_overlap, report.steps, report.phi,
               grains);
    return 3;
  }
  io::claim_output_folder(input.output_folder, earlier, overwrite, what, input_path,
                          "output.folder");
  std::error_code ec;
  std::filesystem::create_directories(input.output_folder, ec);
  if (ec)
    throw InputError(
        input_path, 0, "output.folder",
        fmt::format("a folder that can be created: '{}': {}", input.output_folder, ec.message()));
  const auto base = std::filesystem::path(input.output_folder) / input.output_name;
  write_packing_csv(packing, base.string() + ".csv");
  if (input.write_vtu) write_packing_vtu(packing, base.string() + ".vtu");
  log().info("packing: {} DEM steps in {:.2f} s, wrote {}.csv{}", report.steps, report.wall_seconds,
             base.string(), input.write_vtu ? " and .vtu" : "");
  const bool jam = input.params.method == PackingMethod::kJam;
  fmt::print("{}{}\n", summary_line(packing),
             jam ? fmt::format(", jamming phi = {:.5f}", report.jamming_phi) : std::string());
  return 0;
}

}  // namespace mpmcd::packing
