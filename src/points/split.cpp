#include "mpmcd/points/split.hpp"

#include <algorithm>
#include <stdexcept>

#include "mpmcd/grid/shape.hpp"

namespace mpmcd::points {

void sort_splits(std::vector<Split>& splits) {
  std::sort(splits.begin(), splits.end(),
            [](const Split& a, const Split& b) { return a.point < b.point; });
}

template <int Dim>
std::vector<Split> find_splits(const PointSet<Dim>& points, const std::vector<Grain>& grains,
                               std::span<const std::size_t> which, double h) {
  std::vector<Split> out;
  for (const std::size_t g : which)
    for (std::int64_t p = grains[g].begin; p < grains[g].end; ++p) {
      const Mat<Dim> D = points.F[p] * points.domain[p];
      if (grid::fits_cpdi_window<Dim>(D, h)) continue;
      // The widest axis r (largest row sum of |D|) and the edge that spans most of it.
      Eigen::Index r = 0, k = 0;
      grid::cpdi_half_extents<Dim>(D).maxCoeff(&r);
      D.row(r).cwiseAbs().maxCoeff(&k);
      out.push_back({p, static_cast<std::int32_t>(k)});
    }
  sort_splits(out);
  return out;
}

template <int Dim>
std::vector<std::int64_t> apply_splits(PointSet<Dim>& points, std::vector<Grain>& grains,
                                       std::span<const Split> splits) {
  const auto n = static_cast<std::int64_t>(points.size());
  std::vector<std::int64_t> index(static_cast<std::size_t>(n));
  if (splits.empty()) {
    for (std::int64_t p = 0; p < n; ++p) index[p] = p;
    return index;
  }
  for (std::size_t s = 1; s < splits.size(); ++s)
    if (splits[s].point <= splits[s - 1].point)
      throw std::invalid_argument("apply_splits: points not ascending and distinct");
  // Old point of every new point, and whether it is a split's second child (+ d/2).
  std::vector<std::int64_t> from;
  std::vector<std::int32_t> edge;  // -1: a copy; else the edge of a first (even) or second child
  std::vector<char> second;
  from.reserve(static_cast<std::size_t>(n) + splits.size());
  std::vector<std::int64_t> hist_from;  // old history index of every new history double
  std::size_t s = 0;
  for (auto& gr : grains) {
    const std::int64_t nh =
        gr.size() > 0
            ? ((&gr != &grains.back() ? (&gr + 1)->history_offset
                                      : static_cast<std::int64_t>(points.history.size())) -
               gr.history_offset) /
                  gr.size()
            : 0;
    const auto begin = static_cast<std::int64_t>(from.size());
    const std::size_t s0 = s;
    for (std::int64_t p = gr.begin; p < gr.end; ++p) {
      index[p] = static_cast<std::int64_t>(from.size());
      const bool split = s < splits.size() && splits[s].point == p;
      from.push_back(p);
      edge.push_back(split ? splits[s].edge : -1);
      second.push_back(0);
      if (split) ++s;
    }
    for (std::size_t t = s0; t < s; ++t) {  // the second children, after the grain's points
      from.push_back(splits[t].point);
      edge.push_back(splits[t].edge);
      second.push_back(1);
    }
    const std::int64_t h0 = static_cast<std::int64_t>(hist_from.size());
    for (std::int64_t q = begin; q < static_cast<std::int64_t>(from.size()); ++q)
      for (std::int64_t j = 0; j < nh; ++j)
        hist_from.push_back(gr.history_offset + (from[q] - gr.begin) * nh + j);
    gr.begin = begin;
    gr.end = static_cast<std::int64_t>(from.size());
    gr.history_offset = h0;
  }
  if (s != splits.size()) throw std::invalid_argument("apply_splits: a point outside every grain");
  PointSet<Dim>::for_each_point_field(points, [&](auto& array) {
    auto out = array;
    out.resize(from.size());
    for (std::size_t q = 0; q < from.size(); ++q) out[q] = array[from[q]];
    array.swap(out);
  });
  std::vector<double> history(hist_from.size());
  for (std::size_t q = 0; q < hist_from.size(); ++q) history[q] = points.history[hist_from[q]];
  points.history.swap(history);
  for (std::size_t q = 0; q < from.size(); ++q) {
    if (edge[q] < 0) continue;
    const double sign = second[q] ? 1.0 : -1.0;
    // Half the current half-edge: the child's centre is at x -/+ d [m].
    const Vec<Dim> d = 0.5 * points.F[q] * points.domain[q].col(edge[q]);
    points.x[q] += sign * d;
    points.v[q] += sign * (points.L[q] * d);
    points.mass[q] *= 0.5;
    points.volume0[q] *= 0.5;
    points.volume[q] *= 0.5;
    points.domain[q].col(edge[q]) *= 0.5;
  }
  return index;
}

template std::vector<Split> find_splits<2>(const PointSet<2>&, const std::vector<Grain>&,
                                           std::span<const std::size_t>, double);
template std::vector<Split> find_splits<3>(const PointSet<3>&, const std::vector<Grain>&,
                                           std::span<const std::size_t>, double);
template std::vector<std::int64_t> apply_splits<2>(PointSet<2>&, std::vector<Grain>&,
                                                   std::span<const Split>);
template std::vector<std::int64_t> apply_splits<3>(PointSet<3>&, std::vector<Grain>&,
                                                   std::span<const Split>);

}  // namespace mpmcd::points
