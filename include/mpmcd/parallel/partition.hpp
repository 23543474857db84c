#pragma once
/// Dealing grains to ranks (docs/parallel.md): recursive coordinate bisection of the grain
/// centroids weighted by their work (the default, spatially compact), the published greedy
/// dealing by volume (ranks' grains need not be neighbours), and the imbalance measure.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace mpmcd::parallel {

/// How grains are dealt and contacts solved.
enum class Scheme {
  kPartition,  ///< compact volume-balanced partitions, contacts solved by the ranks owning them
  kMaster,     ///< the published scheme: greedy volume dealing, rank 0 solves every contact
};

/// Parses "partition" / "master"; throws std::invalid_argument otherwise.
Scheme scheme_from_string(const std::string& name);

/// Name of a scheme ("partition" / "master").
std::string to_string(Scheme scheme);

/// Phases of a grain's work (docs/parallel.md "Re-balancing"): 0 = the step's set-up and first
/// Newton iteration (follows the points), 1 and 2 = Newton iterations 1 and 2, 3 = the later
/// ones. The ranks synchronise between phases, so each phase must be balanced on its own.
inline constexpr int kWorkPhases = 4;

/// Recursive coordinate bisection: splits the grains (centroids [m]; weights [-], grain-major
/// with `phases` per grain) into `parts` spatially compact sets, cutting across the longer extent
/// each time (any part count, not only powers of two) where the summed weight splits evenly.
/// With several phases, grains near each cut then move or swap across it while that lowers the
/// sum over phases of |weight on one side - its share|. Returns the part of each grain;
/// deterministic.
std::vector<int> bisection(const std::vector<std::array<double, 2>>& centroids,
                           const std::vector<double>& weights, int parts, int phases = 1);

/// The published dealing: grains by decreasing weight (volume) to the part with the least total
/// so far (ties: lower part). Returns the part of each grain.
std::vector<int> deal_by_volume(const std::vector<double>& weights, int parts);

/// Imbalance sum_k max_p W_pk / sum_k mean_p W_pk [-] (1 = perfect) of the weights summed per
/// part and phase (grain-major, `phases` per grain): the time of phases separated by
/// synchronisations over the time without waiting.
double imbalance(const std::vector<int>& part, const std::vector<double>& weights, int parts,
                 int phases = 1);

}  // namespace mpmcd::parallel
