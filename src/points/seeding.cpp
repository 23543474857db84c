#include "mpmcd/points/seeding.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace mpmcd::points {

template <int Dim>
double ball_measure(double radius) {
  if constexpr (Dim == 2) return std::numbers::pi * radius * radius;
  return 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
}

namespace {
// Visits every lattice site inside the box [lo, hi] (site = origin + (i + 1/2) s).
template <int Dim, class F>
void for_lattice_sites(const Vec<Dim>& origin, double s, const Vec<Dim>& lo, const Vec<Dim>& hi,
                       F&& visit) {
  IVec<Dim> first, last;
  for (int d = 0; d < Dim; ++d) {
    first[d] = static_cast<std::int64_t>(std::ceil((lo[d] - origin[d]) / s - 0.5));
    last[d] = static_cast<std::int64_t>(std::floor((hi[d] - origin[d]) / s - 0.5));
  }
  if ((last - first).minCoeff() < 0) return;
  IVec<Dim> i = first;
  while (true) {
    Vec<Dim> x;
    for (int d = 0; d < Dim; ++d) x[d] = origin[d] + (static_cast<double>(i[d]) + 0.5) * s;
    visit(x);
    int d = 0;
    for (; d < Dim; ++d) {
      if (++i[d] <= last[d]) break;
      i[d] = first[d];
    }
    if (d == Dim) break;
  }
}

template <int Dim>
void scale_volumes(Seeds<Dim>& seeds, double s, double exact) {
  if (seeds.x.empty()) return;
  const double cell = std::pow(s, Dim);
  const double factor = exact / (cell * static_cast<double>(seeds.x.size()));
  seeds.volume.assign(seeds.x.size(), cell * factor);
}
}  // namespace

template <int Dim>
Seeds<Dim> seed_ball(const Vec<Dim>& origin, double h, int ppc, const Vec<Dim>& center,
                     double radius) {
  Seeds<Dim> seeds;
  const double s = lattice_spacing(h, ppc);
  const Vec<Dim> lo = center.array() - radius, hi = center.array() + radius;
  if ((hi - lo).minCoeff() < 0) return seeds;
  for_lattice_sites<Dim>(origin, s, lo, hi, [&](const Vec<Dim>& x) {
    if ((x - center).squaredNorm() < radius * radius) seeds.x.push_back(x);
  });
  scale_volumes(seeds, s, ball_measure<Dim>(radius));
  return seeds;
}

template <int Dim>
Seeds<Dim> seed_box(const Vec<Dim>& origin, double h, int ppc, const Vec<Dim>& lo,
                    const Vec<Dim>& hi) {
  Seeds<Dim> seeds;
  const double s = lattice_spacing(h, ppc);
  if ((hi - lo).minCoeff() <= 0) return seeds;
  for_lattice_sites<Dim>(origin, s, lo, hi, [&](const Vec<Dim>& x) {
    if (((x - lo).array() > 0).all() && ((hi - x).array() > 0).all()) seeds.x.push_back(x);
  });
  scale_volumes(seeds, s, (hi - lo).prod());
  return seeds;
}

Seeds<2> seed_disk_polar(const Vec<2>& center, double radius, double spacing) {
  Seeds<2> seeds;
  if (!(radius > 0) || !(spacing > 0)) return seeds;
  const int n = std::max(1, static_cast<int>(std::lround(radius / spacing - 0.5)));
  const double dr = radius / (n + 0.5);
  // Central point: the disk of radius dr/2, as a square of the same area.
  seeds.x.push_back(center);
  seeds.volume.push_back(std::numbers::pi * 0.25 * dr * dr);
  seeds.domain.push_back(Mat<2>::Identity() * (0.25 * std::sqrt(std::numbers::pi) * dr));
  for (int i = 1; i <= n; ++i) {
    const double r = i * dr;
    const int count = std::max(3, static_cast<int>(std::lround(2 * std::numbers::pi * i)));
    const double dtheta = 2 * std::numbers::pi / count;
    const double phase = (i % 2 == 0) ? 0.5 * dtheta : 0.0;
    for (int k = 0; k < count; ++k) {
      const double th = phase + k * dtheta;
      const Vec<2> er(std::cos(th), std::sin(th)), et(-std::sin(th), std::cos(th));
      seeds.x.push_back(center + r * er);
      seeds.volume.push_back(r * dr * dtheta);  // annulus 2 pi r dr shared by `count` points
      Mat<2> dom;
      dom.col(0) = 0.5 * dr * er;
      dom.col(1) = 0.5 * r * dtheta * et;
      seeds.domain.push_back(dom);
    }
  }
  return seeds;
}

template double ball_measure<2>(double);
template double ball_measure<3>(double);
template Seeds<2> seed_ball<2>(const Vec<2>&, double, int, const Vec<2>&, double);
template Seeds<3> seed_ball<3>(const Vec<3>&, double, int, const Vec<3>&, double);
template Seeds<2> seed_box<2>(const Vec<2>&, double, int, const Vec<2>&, const Vec<2>&);
template Seeds<3> seed_box<3>(const Vec<3>&, double, int, const Vec<3>&, const Vec<3>&);

}  // namespace mpmcd::points
