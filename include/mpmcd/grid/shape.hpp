#pragma once
/// Shape functions as tensor products of 1D weights (method.md §1): linear hat functions and
/// uniform GIMP (uGIMP, Bardenhagen & Kober 2004) with a fixed particle half-width lp.
#include <cmath>
#include <cstdint>
#include <string>

#include "mpmcd/core/types.hpp"

namespace mpmcd::grid {

/// Shape-function family, chosen in the input ([grid] shape_function).
enum class ShapeKind { kLinear, kUGimp };

/// Parses "linear" / "ugimp"; throws InputError otherwise.
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

}  // namespace mpmcd::grid
