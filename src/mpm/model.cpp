#include "mpmcd/mpm/model.hpp"

namespace mpmcd::mpm {

template <int Dim>
Diagnostics<Dim> diagnostics(const Model<Dim>& model) {
  Diagnostics<Dim> d;
  const auto& pts = model.points;
  std::vector<Mat<Dim>> sigma;
  std::vector<double> energy;
  for (const auto& g : model.grains) {
    const auto n = static_cast<std::size_t>(g.size());
    sigma.resize(n);
    energy.resize(n);
    const auto& law = *model.laws[g.material];
    const std::size_t hs = static_cast<std::size_t>(law.history_size());
    std::vector<double> hist_out(hs * n);
    materials::LawBatch<Dim> batch{
        std::span<const Mat<Dim>>(pts.F.data() + g.begin, n),
        std::span<const double>(pts.history.data() + g.history_offset, hs * n),
        std::span<double>(hist_out),
        std::span<Mat<Dim>>(sigma),
        {},
        std::span<double>(energy),
        {}};
    law.evaluate(batch);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t p = static_cast<std::size_t>(g.begin) + i;
      d.mass += pts.mass[p];
      d.momentum += pts.mass[p] * pts.v[p];
      d.kinetic += 0.5 * pts.mass[p] * pts.v[p].squaredNorm();
      d.elastic += pts.volume0[p] * energy[i];
      d.volume += pts.volume[p];
    }
  }
  return d;
}

template Diagnostics<2> diagnostics<2>(const Model<2>&);
template Diagnostics<3> diagnostics<3>(const Model<3>&);

}  // namespace mpmcd::mpm
