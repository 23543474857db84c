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

/// Recursive coordinate bisection: splits the grains (centroids [m], weights [-]) into `parts`
/// spatially compact sets of nearly equal weight, cutting across the longer extent each time
/// (any part count, not only powers of two). Returns the part of each grain; deterministic.
std::vector<int> bisection(const std::vector<std::array<double, 2>>& centroids,
                           const std::vector<double>& weights, int parts);

/// The published dealing: grains by decreasing weight (volume) to the part with the least total
/// so far (ties: lower part). Returns the part of each grain.
std::vector<int> deal_by_volume(const std::vector<double>& weights, int parts);

/// Imbalance max_p W_p / mean_p W_p [-] (1 = perfect) of the weights summed per part.
double imbalance(const std::vector<int>& part, const std::vector<double>& weights, int parts);

}  // namespace mpmcd::parallel
