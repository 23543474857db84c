#include "dem.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace mpmcd::packing::detail {

Dem::Dem(std::vector<double> x, std::vector<double> y, std::vector<double> r0,
         std::array<double, 4> box, const DemSettings& settings)
    : s_(settings), box_(box), x_(std::move(x)), y_(std::move(y)), r0_(std::move(r0)) {
  const std::size_t n = x_.size();
  vx_.assign(n, 0.0);
  vy_.assign(n, 0.0);
  w_.assign(n, 0.0);
  fx_.assign(n, 0.0);
  fy_.assign(n, 0.0);
  tq_.assign(n, 0.0);
  r_ = r0_;
  m_.resize(n);
  im_.resize(n);
  ii_.resize(n);
  double m_min = 1e300;
  for (std::size_t i = 0; i < n; ++i) {
    // Mass of a disk of reduced diameter 2 r0 with the density that gives mass 1 to diameter 1
    // (eq. 6); moment of inertia of a uniform disk m r0^2 / 2.
    m_[i] = 4.0 * r0_[i] * r0_[i];
    im_[i] = 1.0 / m_[i];
    ii_[i] = 1.0 / (0.5 * m_[i] * r0_[i] * r0_[i]);
    m_min = std::min(m_min, m_[i]);
    r0_max_ = std::max(r0_max_, r0_[i]);
  }
  // Time step: a tenth of the contact period scale sqrt(m_min / k_n) (§2).
  dt_ = 0.1 * std::sqrt(m_min);
}

void Dem::set_scale(double scale) {
  scale_ = scale;
  for (std::size_t i = 0; i < r_.size(); ++i) r_[i] = scale * r0_[i];
}

void Dem::set_positions(const std::vector<double>& x, const std::vector<double>& y) {
  x_ = x;
  y_ = y;
  built_ = false;
}

void Dem::wrap() {
  if (!s_.periodic) return;
  const double lx = box_[2] - box_[0], ly = box_[3] - box_[1];
  for (std::size_t i = 0; i < x_.size(); ++i) {
    x_[i] -= lx * std::floor((x_[i] - box_[0]) / lx);
    y_[i] -= ly * std::floor((y_[i] - box_[1]) / ly);
    // floor can round a value just below the upper bound up to it: keep [lo, hi).
    if (x_[i] >= box_[2]) x_[i] = box_[0];
    if (y_[i] >= box_[3]) y_[i] = box_[1];
  }
}

void Dem::zero_velocities() {
  std::fill(vx_.begin(), vx_.end(), 0.0);
  std::fill(vy_.begin(), vy_.end(), 0.0);
  std::fill(w_.begin(), w_.end(), 0.0);
}

double Dem::kinetic_energy() const {
  double e = 0.0;
  for (std::size_t i = 0; i < x_.size(); ++i)
    e += 0.5 * m_[i] * (vx_[i] * vx_[i] + vy_[i] * vy_[i]) + 0.5 * w_[i] * w_[i] / ii_[i];
  return e;
}

double Dem::max_force() const {
  double f2 = 0.0;
  for (std::size_t i = 0; i < x_.size(); ++i) f2 = std::max(f2, fx_[i] * fx_[i] + fy_[i] * fy_[i]);
  return std::sqrt(f2);
}

void Dem::build_neighbours() {
  const std::size_t n = x_.size();
  // Old list kept to carry the tangential springs over (eq. 4).
  std::vector<std::int64_t> old_start;
  std::vector<std::int32_t> old_j;
  std::vector<double> old_xi;
  const bool carry = s_.friction > 0.0 && built_;
  if (carry) {
    old_start.swap(nb_start_);
    old_j.swap(nb_j_);
    old_xi.swap(nb_xi_);
  }
  nb_start_.assign(n + 1, 0);
  nb_j_.clear();
  nb_xi_.clear();
  ref_x_ = x_;
  ref_y_ = y_;
  ref_scale_ = scale_;
  built_ = true;
  if (n == 0) return;

  // Cell lists (linked cells by counting sort): cells of width >= 2 r_max + skin, so that every
  // pair within reach lies in the same or an adjacent cell. Periodic cells span the box and wrap
  // around (at least 3 cells per axis, else all pairs are tested).
  const bool per = s_.periodic;
  const double lx = box_[2] - box_[0], ly = box_[3] - box_[1];
  if (per) wrap();
  double lox = x_[0], hix = x_[0], loy = y_[0], hiy = y_[0];
  for (std::size_t i = 1; i < n; ++i) {
    lox = std::min(lox, x_[i]);
    hix = std::max(hix, x_[i]);
    loy = std::min(loy, y_[i]);
    hiy = std::max(hiy, y_[i]);
  }
  if (per) {
    lox = box_[0];
    hix = box_[2];
    loy = box_[1];
    hiy = box_[3];
  }
  const double reach = 2.0 * scale_ * r0_max_ + s_.skin;
  const auto cells_along = [&](double extent) {
    const double c = std::floor(extent / reach);
    return static_cast<std::int64_t>(std::clamp(c, 1.0, 4096.0));
  };
  std::int64_t ncx = cells_along(hix - lox), ncy = cells_along(hiy - loy);
  const bool all_pairs = per && (ncx < 3 || ncy < 3);
  if (all_pairs) ncx = ncy = 1;
  const double wx = per ? (hix - lox) / static_cast<double>(ncx)
                        : std::max((hix - lox) / static_cast<double>(ncx), reach);
  const double wy = per ? (hiy - loy) / static_cast<double>(ncy)
                        : std::max((hiy - loy) / static_cast<double>(ncy), reach);
  const auto cell_of = [&](double v, double lo, double w, std::int64_t nc) {
    return std::clamp(static_cast<std::int64_t>((v - lo) / w), std::int64_t{0}, nc - 1);
  };
  std::vector<std::int32_t> cell(n);
  cell_start_.assign(static_cast<std::size_t>(ncx * ncy + 1), 0);
  for (std::size_t i = 0; i < n; ++i) {
    cell[i] = static_cast<std::int32_t>(cell_of(y_[i], loy, wy, ncy) * ncx +
                                        cell_of(x_[i], lox, wx, ncx));
    ++cell_start_[cell[i] + 1];
  }
  std::partial_sum(cell_start_.begin(), cell_start_.end(), cell_start_.begin());
  cell_items_.resize(n);
  {
    std::vector<std::int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
    for (std::size_t i = 0; i < n; ++i) cell_items_[fill[cell[i]]++] = static_cast<std::int32_t>(i);
  }
  const std::int64_t span = all_pairs ? 0 : 1;
  for (std::size_t i = 0; i < n; ++i) {
    const std::int64_t cx = cell[i] % ncx, cy = cell[i] / ncx;
    const std::size_t row = nb_j_.size();
    for (std::int64_t oy = -span; oy <= span; ++oy) {
      std::int64_t ey = cy + oy;
      if (per) ey = (ey + ncy) % ncy;
      if (ey < 0 || ey >= ncy) continue;
      for (std::int64_t ox = -span; ox <= span; ++ox) {
        std::int64_t ex = cx + ox;
        if (per) ex = (ex + ncx) % ncx;
        if (ex < 0 || ex >= ncx) continue;
        const std::int64_t c = ey * ncx + ex;
        for (std::int32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
          const std::int32_t j = cell_items_[k];
          if (static_cast<std::size_t>(j) <= i) continue;
          const double dx = image(x_[j] - x_[i], lx), dy = image(y_[j] - y_[i], ly);
          const double cut = r_[i] + r_[j] + s_.skin;
          if (dx * dx + dy * dy < cut * cut) nb_j_.push_back(j);
        }
      }
    }
    std::sort(nb_j_.begin() + static_cast<std::ptrdiff_t>(row), nb_j_.end());
    nb_start_[i + 1] = static_cast<std::int64_t>(nb_j_.size());
  }
  nb_xi_.assign(nb_j_.size(), 0.0);
  if (carry) {
    for (std::size_t i = 0; i < n; ++i) {
      const auto ob = old_j.begin() + old_start[i], oe = old_j.begin() + old_start[i + 1];
      for (std::int64_t k = nb_start_[i]; k < nb_start_[i + 1]; ++k) {
        const auto it = std::lower_bound(ob, oe, nb_j_[k]);
        if (it != oe && *it == nb_j_[k]) nb_xi_[k] = old_xi[it - old_j.begin()];
      }
    }
  }
}

void Dem::maybe_rebuild() {
  if (!built_) {
    build_neighbours();
    return;
  }
  // A pair absent from the list had a gap > skin at build time; the gap shrinks by at most the
  // two displacements plus the two radius increases, so rebuild before 2 (d_max + dr_max) > skin.
  double d2 = 0.0;
  const double lx = box_[2] - box_[0], ly = box_[3] - box_[1];
  for (std::size_t i = 0; i < x_.size(); ++i) {
    const double dx = image(x_[i] - ref_x_[i], lx), dy = image(y_[i] - ref_y_[i], ly);
    d2 = std::max(d2, dx * dx + dy * dy);
  }
  const double dr = std::max(0.0, (scale_ - ref_scale_) * r0_max_);
  if (2.0 * (std::sqrt(d2) + dr) > s_.skin) build_neighbours();
}

void Dem::compute_forces(bool viscous, double dt) {
  const std::size_t n = x_.size();
  std::fill(fx_.begin(), fx_.end(), 0.0);
  std::fill(fy_.begin(), fy_.end(), 0.0);
  std::fill(tq_.begin(), tq_.end(), 0.0);
  double max_ov = 0.0, energy = 0.0;
  const bool hertz = s_.law == ContactLaw::kHertz;
  const bool friction = s_.friction > 0.0;
  const double kt = s_.tangential_ratio;  // k_n = 1
  // Elastic normal force (eq. 1 linear, eq. 2 Hertz) and its energy.
  const auto elastic = [&](double delta, double rstar, double& e) {
    if (hertz) {
      const double root = std::sqrt(rstar * delta);
      e += 0.4 * root * delta * delta;
      return root * delta;
    }
    e += 0.5 * delta * delta;
    return delta;
  };
  const double lx = box_[2] - box_[0], ly = box_[3] - box_[1];
  for (std::size_t i = 0; i < n; ++i) {
    const double xi = x_[i], yi = y_[i], ri = r_[i];
    double fxi = 0.0, fyi = 0.0, tqi = 0.0;
    for (std::int64_t k = nb_start_[i]; k < nb_start_[i + 1]; ++k) {
      const std::int32_t j = nb_j_[k];
      const double dx = image(x_[j] - xi, lx), dy = image(y_[j] - yi, ly), rs = ri + r_[j];
      const double d2 = dx * dx + dy * dy;
      if (d2 >= rs * rs) {
        nb_xi_[k] = 0.0;
        continue;
      }
      const double d = std::sqrt(d2);
      const double nx = d > 0.0 ? dx / d : 1.0, ny = d > 0.0 ? dy / d : 0.0;
      const double delta = rs - d;
      max_ov = std::max(max_ov, delta);
      double fn = elastic(delta, ri * r_[j] / rs, energy);
      const double dvx = vx_[i] - vx_[j], dvy = vy_[i] - vy_[j];
      if (viscous) {
        // Normal viscous damping (eq. 3): gamma_n = 2 zeta sqrt(m* k_n), m* reduced mass.
        const double mstar = m_[i] * m_[j] / (m_[i] + m_[j]);
        fn = std::max(0.0, fn + 2.0 * s_.damping_ratio * std::sqrt(mstar) * (dvx * nx + dvy * ny));
      }
      fxi -= fn * nx;
      fyi -= fn * ny;
      fx_[j] += fn * nx;
      fy_[j] += fn * ny;
      if (friction) {
        // Tangential spring with Coulomb cap (eq. 4), t = n rotated by +90 degrees.
        const double tx = -ny, ty = nx;
        const double vt = dvx * tx + dvy * ty + w_[i] * ri + w_[j] * r_[j];
        double& xit = nb_xi_[k];
        xit += vt * dt;
        double ft = -kt * xit;
        const double cap = s_.friction * fn;
        if (std::abs(ft) > cap) {
          ft = std::copysign(cap, ft);
          xit = -ft / kt;
        }
        fxi += ft * tx;
        fyi += ft * ty;
        fx_[j] -= ft * tx;
        fy_[j] -= ft * ty;
        tqi += ri * ft;
        tq_[j] += r_[j] * ft;
      }
    }
    // Frictionless rigid walls, same normal law with R* = r_i and m* = m_i (§2).
    const double gap[4] = {xi - box_[0], yi - box_[1], box_[2] - xi, box_[3] - yi};
    const double vn[4] = {wall_v_[0] - vx_[i], wall_v_[1] - vy_[i], vx_[i] - wall_v_[2],
                          vy_[i] - wall_v_[3]};
    const double sign[4] = {1.0, 1.0, -1.0, -1.0};
    for (int wdx = 0; wdx < (s_.periodic ? 0 : 4); ++wdx) {
      const double delta = ri - gap[wdx];
      if (delta <= 0.0) continue;
      max_ov = std::max(max_ov, delta);
      double fn = elastic(delta, ri, energy);
      if (viscous) fn = std::max(0.0, fn + 2.0 * s_.damping_ratio * std::sqrt(m_[i]) * vn[wdx]);
      if (wdx % 2 == 0)
        fxi += sign[wdx] * fn;
      else
        fyi += sign[wdx] * fn;
    }
    if (viscous) {
      // Background drag (eq. 5).
      fxi -= s_.global_damping * m_[i] * vx_[i];
      fyi -= s_.global_damping * m_[i] * vy_[i];
      tqi -= s_.global_damping * w_[i] / ii_[i];
    }
    fx_[i] += fxi;
    fy_[i] += fyi;
    tq_[i] += tqi;
  }
  max_overlap_ = max_ov;
  energy_ = energy;
}

void Dem::update_forces(bool viscous) {
  maybe_rebuild();
  compute_forces(viscous, 0.0);
}

void Dem::md_step(double dt) {
  // Velocity Verlet (eq. 7); the viscous forces use the half-step velocities.
  const std::size_t n = x_.size();
  if (!built_) update_forces(true);
  const bool spin = s_.friction > 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    vx_[i] += 0.5 * dt * fx_[i] * im_[i];
    vy_[i] += 0.5 * dt * fy_[i] * im_[i];
    x_[i] += dt * vx_[i];
    y_[i] += dt * vy_[i];
    if (spin) w_[i] += 0.5 * dt * tq_[i] * ii_[i];
  }
  maybe_rebuild();
  compute_forces(true, dt);
  for (std::size_t i = 0; i < n; ++i) {
    vx_[i] += 0.5 * dt * fx_[i] * im_[i];
    vy_[i] += 0.5 * dt * fy_[i] * im_[i];
    if (spin) w_[i] += 0.5 * dt * tq_[i] * ii_[i];
  }
  ++steps_;
}

MinimizeResult Dem::minimize(std::int64_t max_steps, double overlap_stop, double energy_stop,
                             double force_stop) {
  // FIRE 2.0 (Guenole et al., Comput. Mater. Sci. 175 (2020) 109584, Algorithm 2) with
  // semi-implicit Euler steps; parameters of their Table 1.
  const std::size_t n = x_.size();
  // dt_max = 5 dt (not their 10 dt): measured 10-20 times faster near jamming (§7).
  const double dt_max = 5.0 * dt_, dt_min = 0.02 * dt_;
  const double alpha0 = 0.1, f_inc = 1.1, f_dec = 0.5, f_alpha = 0.99;
  const std::int64_t n_delay = 20;
  double dt = dt_, alpha = alpha0;
  std::int64_t n_pos = 0;
  MinimizeResult res;
  zero_velocities();
  update_forces(false);
  const double nd = static_cast<double>(std::max<std::size_t>(n, 1));
  for (std::int64_t it = 0; it < max_steps; ++it) {
    const double fmax = max_force();
    if (max_overlap_ < overlap_stop || energy_ / nd < energy_stop ||
        fmax < force_stop * std::sqrt(2.0 * energy_ / nd)) {
      res.converged = true;
      break;
    }
    double p = 0.0;
    for (std::size_t i = 0; i < n; ++i) p += fx_[i] * vx_[i] + fy_[i] * vy_[i];
    if (p > 0.0) {
      if (++n_pos > n_delay) {
        dt = std::min(dt * f_inc, dt_max);
        alpha *= f_alpha;
      }
    } else {
      n_pos = 0;
      if (it >= n_delay) dt = std::max(dt * f_dec, dt_min);
      alpha = alpha0;
      for (std::size_t i = 0; i < n; ++i) {
        x_[i] -= 0.5 * dt * vx_[i];
        y_[i] -= 0.5 * dt * vy_[i];
      }
      zero_velocities();
    }
    // Semi-implicit Euler with the FIRE velocity mixing v <- (1 - a) v + a |v| F / |F|.
    double v2 = 0.0, f2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      vx_[i] += dt * fx_[i] * im_[i];
      vy_[i] += dt * fy_[i] * im_[i];
      v2 += vx_[i] * vx_[i] + vy_[i] * vy_[i];
      f2 += fx_[i] * fx_[i] + fy_[i] * fy_[i];
    }
    const double mix = f2 > 0.0 ? alpha * std::sqrt(v2 / f2) : 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      vx_[i] = (1.0 - alpha) * vx_[i] + mix * fx_[i];
      vy_[i] = (1.0 - alpha) * vy_[i] + mix * fy_[i];
      x_[i] += dt * vx_[i];
      y_[i] += dt * vy_[i];
    }
    maybe_rebuild();
    compute_forces(false, 0.0);
    ++res.steps;
    ++steps_;
  }
  res.energy_per_disk = energy_ / nd;
  res.max_force = max_force();
  if (!res.converged)
    res.converged = max_overlap_ < overlap_stop || res.energy_per_disk < energy_stop ||
                    res.max_force < force_stop * std::sqrt(2.0 * res.energy_per_disk);
  zero_velocities();
  return res;
}

}  // namespace mpmcd::packing::detail
