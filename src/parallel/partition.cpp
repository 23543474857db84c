#include "mpmcd/parallel/partition.hpp"

#include <algorithm>
#include <numeric>
#include <stdexcept>

namespace mpmcd::parallel {

Scheme scheme_from_string(const std::string& name) {
  if (name == "partition") return Scheme::kPartition;
  if (name == "master") return Scheme::kMaster;
  throw std::invalid_argument("expected \"partition\" or \"master\", got \"" + name + "\"");
}

std::string to_string(Scheme scheme) {
  return scheme == Scheme::kMaster ? "master" : "partition";
}

namespace {

void bisect(const std::vector<std::array<double, 2>>& c, const std::vector<double>& w,
            std::vector<std::size_t> ids, int first_part, int parts, std::vector<int>& out) {
  if (parts <= 1 || ids.size() <= 1) {
    for (std::size_t i : ids) out[i] = first_part;
    return;
  }
  // Cut across the longer extent of the centroids.
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (std::size_t i : ids)
    for (int d = 0; d < 2; ++d) {
      lo[d] = std::min(lo[d], c[i][d]);
      hi[d] = std::max(hi[d], c[i][d]);
    }
  const int axis = (hi[1] - lo[1]) > (hi[0] - lo[0]) ? 1 : 0;
  std::sort(ids.begin(), ids.end(), [&](std::size_t a, std::size_t b) {
    if (c[a][axis] != c[b][axis]) return c[a][axis] < c[b][axis];
    return a < b;  // deterministic ties
  });
  const int left_parts = parts / 2;
  double total = 0;
  for (std::size_t i : ids) total += w[i];
  const double target = total * left_parts / parts;
  // The cut that brings the left weight closest to its share.
  double acc = 0;
  std::size_t cut = 0;
  double best = 1e300;
  for (std::size_t k = 0; k <= ids.size(); ++k) {
    const double err = std::abs(acc - target);
    if (err < best) {
      best = err;
      cut = k;
    }
    if (k < ids.size()) acc += w[ids[k]];
  }
  cut = std::clamp<std::size_t>(cut, 1, ids.size() - 1);
  std::vector<std::size_t> left(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(cut));
  std::vector<std::size_t> right(ids.begin() + static_cast<std::ptrdiff_t>(cut), ids.end());
  bisect(c, w, std::move(left), first_part, left_parts, out);
  bisect(c, w, std::move(right), first_part + left_parts, parts - left_parts, out);
}

}  // namespace

std::vector<int> bisection(const std::vector<std::array<double, 2>>& centroids,
                           const std::vector<double>& weights, int parts) {
  std::vector<int> out(centroids.size(), 0);
  std::vector<std::size_t> ids(centroids.size());
  std::iota(ids.begin(), ids.end(), std::size_t{0});
  bisect(centroids, weights, std::move(ids), 0, std::max(parts, 1), out);
  return out;
}

std::vector<int> deal_by_volume(const std::vector<double>& weights, int parts) {
  std::vector<std::size_t> ids(weights.size());
  std::iota(ids.begin(), ids.end(), std::size_t{0});
  std::stable_sort(ids.begin(), ids.end(),
                   [&](std::size_t a, std::size_t b) { return weights[a] > weights[b]; });
  std::vector<double> load(static_cast<std::size_t>(std::max(parts, 1)), 0.0);
  std::vector<int> out(weights.size(), 0);
  for (std::size_t i : ids) {
    const auto p = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    out[i] = p;
    load[p] += weights[i];
  }
  return out;
}

double imbalance(const std::vector<int>& part, const std::vector<double>& weights, int parts) {
  std::vector<double> load(static_cast<std::size_t>(std::max(parts, 1)), 0.0);
  for (std::size_t i = 0; i < part.size(); ++i) load[part[i]] += weights[i];
  const double mean = std::accumulate(load.begin(), load.end(), 0.0) / load.size();
  return mean > 0 ? *std::max_element(load.begin(), load.end()) / mean : 1.0;
}

}  // namespace mpmcd::parallel
