#pragma once
/// Shape functions (method.md §1): tensor products of 1D weights (linear hat functions and uniform
/// GIMP, uGIMP, Bardenhagen & Kober 2004, with a fixed particle half-width lp), and CPDI1
/// (Sadeghirad, Brannon & Burghardt 2011), whose point domains follow the deformation gradient.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "mpmcd/core/types.hpp"

namespace mpmcd::grid {

/// Shape-function family, chosen in the input ([grid] shape_function).
enum class ShapeKind { kLinear, kUGimp, kCpdi };

/// Parses "linear" / "ugimp" / "cpdi"; throws InputError otherwise.
ShapeKind shape_kind_from_string(const std::string& name);

/// 1D linear hat weights: N(d) = 1 - |d|/h on two nodes.
struct Linear1D {
  static constexpr int kNodes = 2;  ///< nodes per axis in the support
  /// `xi` = (x - origin)/h [-]; writes the first node index and the weights / derivatives [1/m].
  static void eval(double xi, double h, double /*lp*/, std::int64_t& first, double* N, double* dN) {
    const double f = std::floor(xi);
    first = static_cast<std::int64_t>(f);
    const double t = xi - f;
    N[0] = 1.0 - t;
    N[1] = t;
    dN[0] = -1.0 / h;
    dN[1] = 1.0 / h;
  }
};

/// 1D uGIMP weights for a particle of half-width lp < h/2 (Bardenhagen & Kober 2004, eq. for the
/// convolution of the hat function with a box of width 2 lp), on three nodes around the nearest
/// one:
///   |d| < lp:            S = 1 - (d^2 + lp^2) / (2 h lp)
///   lp <= |d| <= h - lp: S = 1 - |d| / h
///   h - lp < |d| < h+lp: S = (h + lp - |d|)^2 / (4 h lp)
struct UGimp1D {
  static constexpr int kNodes = 3;  ///< nodes per axis in the support
  /// One weight and its derivative [1/m] at signed distance d = x - x_node [m].
  static void weight(double d, double h, double lp, double& S, double& dS) {
    const double r = std::abs(d);
    const double s = d < 0 ? -1.0 : 1.0;
    if (r < lp) {
      S = 1.0 - (d * d + lp * lp) / (2.0 * h * lp);
      dS = -d / (h * lp);
    } else if (r <= h - lp) {
      S = 1.0 - r / h;
      dS = -s / h;
    } else if (r < h + lp) {
      const double q = h + lp - r;
      S = q * q / (4.0 * h * lp);
      dS = -s * q / (2.0 * h * lp);
    } else {
      S = 0.0;
      dS = 0.0;
    }
  }
  /// `xi` = (x - origin)/h [-]; writes the first node index and the weights / derivatives [1/m].
  static void eval(double xi, double h, double lp, std::int64_t& first, double* N, double* dN) {
    const auto nearest = static_cast<std::int64_t>(std::floor(xi + 0.5));
    first = nearest - 1;
    for (int a = 0; a < 3; ++a)
      weight((xi - static_cast<double>(first + a)) * h, h, lp, N[a], dN[a]);
  }
};

/// Number of support nodes of a point: kNodes^Dim.
template <int Dim, class S1>
constexpr int support_size() {
  int k = 1;
  for (int d = 0; d < Dim; ++d) k *= S1::kNodes;
  return k;
}

/// Tensor-product shape functions of one point: first node coordinates, weights and gradients.
template <int Dim, class S1>
struct PointShape {
  static constexpr int K = support_size<Dim, S1>();  ///< support size
  IVec<Dim> first;                                   ///< integer coordinates of the first node
  double N[K];                                       ///< weights, sum = 1 [-]
  Vec<Dim> dN[K];                                    ///< gradients [1/m]
  /// Offset of support node a along axis d (0 .. kNodes-1).
  static int offset(int a, int d) {
    for (int e = 0; e < d; ++e) a /= S1::kNodes;
    return a % S1::kNodes;
  }
  /// Same as eval(x, origin, h, lp); the current domain is not used by these functions. Always
  /// true (the support is always kNodes per axis).
  bool eval(const Vec<Dim>& x, const Vec<Dim>& origin, double h, double lp,
            const Mat<Dim>& /*domain*/) {
    eval(x, origin, h, lp);
    return true;
  }
  /// Evaluates at x [m] on a grid of `origin` [m], cell size `h` [m], uGIMP half-width `lp` [m].
  void eval(const Vec<Dim>& x, const Vec<Dim>& origin, double h, double lp) {
    double n1[Dim][S1::kNodes], d1[Dim][S1::kNodes];
    for (int d = 0; d < Dim; ++d) {
      std::int64_t f;
      S1::eval((x[d] - origin[d]) / h, h, lp, f, n1[d], d1[d]);
      first[d] = f;
    }
    for (int a = 0; a < K; ++a) {
      double w = 1.0;
      for (int d = 0; d < Dim; ++d) w *= n1[d][offset(a, d)];
      N[a] = w;
      for (int d = 0; d < Dim; ++d) {
        double g = d1[d][offset(a, d)];
        for (int e = 0; e < Dim; ++e)
          if (e != d) g *= n1[e][offset(a, e)];
        dN[a][d] = g;
      }
    }
  }
};

/// Tag of the CPDI1 family: a point's support is a window of 3 nodes per axis (the cells holding
/// the corners of its domain, which must span at most two cells per axis).
struct Cpdi1D {
  static constexpr int kNodes = 3;  ///< nodes per axis in the support window
};

/// Largest half-extent along an axis [m] of a domain whose corners fit the CPDI1 window of a grid
/// of cell size `h` [m]: a bounding box at most one cell wide spans at most two cells.
inline double cpdi_window_half_extent(double h) {
  return 0.5 * h * (1.0 - 1e-9);
}

/// Half-extents of the domain D [m] (columns: half-edges) along each axis, the row sums of |D| [m].
template <int Dim>
Vec<Dim> cpdi_half_extents(const Mat<Dim>& D) {
  return D.cwiseAbs().rowwise().sum();
}

/// True when the domain D [m] (columns: half-edges) fits the CPDI1 window on cells of size h [m].
template <int Dim>
bool fits_cpdi_window(const Mat<Dim>& D, double h) {
  return cpdi_half_extents<Dim>(D).maxCoeff() <= cpdi_window_half_extent(h);
}

/// The domain D [m] (columns: half-edges) scaled down about the point until its bounding box is
/// at most one cell h [m] wide along every axis, so that its corners span at most two cells (the
/// CPDI1 window); D itself when it already fits. The scaled domain still gives a partition of
/// unity with exact linear fields, but no longer tiles the body with its neighbours.
template <int Dim>
Mat<Dim> fit_cpdi_window(const Mat<Dim>& D, double h) {
  const double half = cpdi_half_extents<Dim>(D).maxCoeff();  // largest half-extent [m]
  const double limit = cpdi_window_half_extent(h);
  return half <= limit ? D : Mat<Dim>(D * (limit / half));
}

/// CPDI1 weights of one point (Sadeghirad et al. 2011, eqs. 31-32, written for any Dim): the
/// point's domain is the parallelepiped x_p + D s, s in [-1, 1]^Dim, D = F D0 (columns: current
/// half-edge vectors [m]); with the linear hat N_I at its 2^Dim corners x_c = x_p + D s_c,
///   N_I(x_p)      = 2^-Dim sum_c N_I(x_c)                 (mean of the corner interpolant),
///   grad N_I(x_p) = 2^-Dim D^-T sum_c s_c N_I(x_c)         (exact mean of its gradient).
/// Domains that tile a body keep tiling it under any homogeneous F, so a uniform stress gives no
/// force at interior nodes whatever the points' positions relative to the grid lines.
template <int Dim>
struct CpdiShape {
  static constexpr int K = support_size<Dim, Cpdi1D>();  ///< support window size (3^Dim)
  IVec<Dim> first;                                       ///< integer coordinates of the first node
  double N[K];                                           ///< weights, sum = 1 [-]
  Vec<Dim> dN[K];                                        ///< gradients [1/m]
  /// Offset of window node a along axis d (0 .. 2).
  static int offset(int a, int d) { return PointShape<Dim, Cpdi1D>::offset(a, d); }
  /// Evaluates at x [m] for the current domain D [m] (columns: half-edges) on a grid of `origin`
  /// [m] and cell size `h` [m]; false if the corners span more than two cells along an axis.
  bool eval(const Vec<Dim>& x, const Vec<Dim>& origin, double h, double /*lp*/,
            const Mat<Dim>& domain) {
    constexpr int nc = 1 << Dim;
    Vec<Dim> xi[nc];
    for (int c = 0; c < nc; ++c) {
      Vec<Dim> s;
      for (int d = 0; d < Dim; ++d) s[d] = (c >> d) & 1 ? 1.0 : -1.0;
      xi[c] = (x + domain * s - origin) / h;
    }
    for (int d = 0; d < Dim; ++d) {
      double lo = xi[0][d];
      for (int c = 1; c < nc; ++c) lo = std::min(lo, xi[c][d]);
      first[d] = static_cast<std::int64_t>(std::floor(lo));
    }
    Vec<Dim> ssum[K];
    for (int a = 0; a < K; ++a) {
      N[a] = 0.0;
      ssum[a].setZero();
    }
    for (int c = 0; c < nc; ++c) {
      // Linear hat weights of corner c on the 2^Dim nodes of its cell, placed in the window.
      int o[Dim];
      double t[Dim];
      for (int d = 0; d < Dim; ++d) {
        double f = std::floor(xi[c][d]);
        // A corner on the window's last grid line belongs to the cell below it (weight 1 there).
        if (f - static_cast<double>(first[d]) > 1.5 && xi[c][d] - f < 1e-12) f -= 1.0;
        o[d] = static_cast<int>(f - static_cast<double>(first[d]));
        if (o[d] < 0 || o[d] > 1) return false;
        t[d] = xi[c][d] - f;
      }
      for (int b = 0; b < nc; ++b) {
        double w = 1.0;
        int a = 0, mul = 1;
        for (int d = 0; d < Dim; ++d) {
          const int up = (b >> d) & 1;
          w *= up ? t[d] : 1.0 - t[d];
          a += (o[d] + up) * mul;
          mul *= 3;
        }
        N[a] += w;
        for (int d = 0; d < Dim; ++d) ssum[a][d] += ((c >> d) & 1 ? w : -w);
      }
    }
    const Mat<Dim> dinvT = domain.inverse().transpose();
    for (int a = 0; a < K; ++a) {
      N[a] /= nc;
      dN[a] = dinvT * ssum[a] / nc;
    }
    return true;
  }
};

/// The point-shape type of a family tag: PointShape for Linear1D / UGimp1D, CpdiShape for Cpdi1D.
template <int Dim, class S1>
struct ShapeOf {
  using type = PointShape<Dim, S1>;  ///< tensor-product shape
};
/// CPDI1 specialisation.
template <int Dim>
struct ShapeOf<Dim, Cpdi1D> {
  using type = CpdiShape<Dim>;  ///< CPDI1 shape
};

}  // namespace mpmcd::grid
