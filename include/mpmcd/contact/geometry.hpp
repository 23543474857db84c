#pragma once
/// The geometry of contact detection (method.md §4, docs/contact.md, docs/accuracy.md) as free
/// functions on plain views: a point's domain x + F D0 s, s in [-1, 1]^Dim (its extent along a
/// direction, its reach, its face toward a normal and that face's corners, the entry of a ray into
/// it), the gap between the domains of two point sets, the gap of a grain node near a wall, the
/// faces of a grain facing a wall, and the linear hat weights of positions at a grain's nodes.
/// mpm::ImplicitSolver calls them on its points and grain fields (tests/unit/contact).
#include <cstdint>
#include <span>
#include <vector>

#include "mpmcd/core/types.hpp"
#include "mpmcd/walls/wall.hpp"

namespace mpmcd::contact {

/// The points' domains x + F D0 s, s in [-1, 1]^Dim: views of a point set's arrays, indexed by
/// point (mpm: PointSet::x, F, domain).
template <int Dim>
struct DomainsView {
  std::span<const Vec<Dim>> x;       ///< centres [m]
  std::span<const Mat<Dim>> F;       ///< deformation gradients [-]
  std::span<const Mat<Dim>> domain;  ///< reference half-edge vectors D0 (columns) [m]
};

/// Extent of the domain F D0 along the unit vector n: sum_i |n . F r_i|, r_i the columns of D0,
/// computed as |D0^T (F^T n)|_1 [m] (lp |F^T n|_1 for a lattice square of half-edge lp).
template <int Dim>
double domain_extent(const Mat<Dim>& F, const Mat<Dim>& D0, const Vec<Dim>& n);

/// Reach of the domain D = F D0: sum_i |D e_i|, a bound of its extent along any unit vector [m].
template <int Dim>
double domain_reach(const Mat<Dim>& D);

/// The 2^(Dim-1) corners x + D s of the face s_axis = sign (sign = +-1) of the domain x + D s
/// [m], appended to `corners` in the order of the bits of the other axes (bit set: s_d = +1).
template <int Dim>
void face_corners(const Vec<Dim>& x, const Mat<Dim>& D, int axis, double sign,
                  std::vector<Vec<Dim>>& corners);

/// Outward unit normal of the face s_axis = sign (sign = +-1) of the domain x + D s: the row
/// `axis` of D^-1 (m = D^-T e_axis), times sign / |m|, as grain_face_contacts takes it [-].
template <int Dim>
Vec<Dim> face_normal(const Mat<Dim>& D, int axis, double sign);

/// Derivative of a face's unit normal n (face_normal of D = dF D^n) with respect to the
/// increment du_J of one grid node J, when dF = I + sum_J du_J (x) grad N_J(x^n) moves the
/// domain: dn = -(I - n n^T) g_J (n . du_J), so the Dim x Dim matrix -(I - n n^T) g_J n^T, with
/// g_J = dF^-T grad N_J(x^n) the node's shape gradient at x^{n+1} [1/m] (exact, from
/// d(dF^-T) = -dF^-T d(dF)^T dF^-T; docs/contact.md, "Face normals at the end of the step").
template <int Dim>
Mat<Dim> face_normal_derivative(const Vec<Dim>& n, const Vec<Dim>& g);

/// The face of the domain x + D s facing a wall of unit normal n (into the domain): s_k =
/// -sign(m_k . n) on the axis k whose face normal m_k = D^-T e_k is the most nearly parallel to n,
/// whatever the domain's small shear or rotation. Appends its corners (face_corners) and returns
/// its centre x + D s [m].
template <int Dim>
Vec<Dim> face_toward(const Vec<Dim>& x, const Mat<Dim>& D, const Vec<Dim>& n,
                     std::vector<Vec<Dim>>& corners);

/// Gap of the domains of points p and q along their centre line: |x_q - x_p| minus both domains'
/// extents along it (negative: they overlap) [m]; not defined for coincident centres.
template <int Dim>
double pair_gap(const DomainsView<Dim>& pts, std::int64_t p, std::int64_t q);

/// Smallest pair_gap between a domain of the points a0 + a[i] and one of the points b0 + b[j]
/// [m] (0 as soon as two centres coincide; +infinity for an empty set). `reach` (per point,
/// domain_reach) skips the pairs whose centre distance minus both reaches is not below the gap
/// found so far (the same result, far fewer extents).
template <int Dim>
double nearest_gap(const DomainsView<Dim>& pts, std::span<const double> reach, std::int64_t a0,
                   std::span<const std::int32_t> a, std::int64_t b0,
                   std::span<const std::int32_t> b);

/// Entry distance t of the ray x + t nu [m] into the domain x_q + D s, |s_i| <= 1, given D^-1
/// (`dinv`, [1/m]) (slab test); +infinity when the ray misses it or the domain lies behind x [m].
template <int Dim>
double ray_entry(const Vec<Dim>& x_q, const Mat<Dim>& dinv, const Vec<Dim>& x, const Vec<Dim>& nu);

/// Gap of a grain node at x_node [m] from `wall` at time t [s], from the domains of the node's
/// points p0 + local[i]: the smallest wall distance of a domain's face (distance minus extent
/// along the normal), and at least the node's distance minus twice the largest extent (a node
/// inside the grain may approach the wall until one whole domain still fits between them) [m];
/// +infinity when the node has no point.
template <int Dim>
double node_wall_gap(const walls::Wall<Dim>& wall, double t, const Vec<Dim>& x_node,
                     const DomainsView<Dim>& pts, std::int64_t p0,
                     std::span<const std::int32_t> local);

/// A point's domain face toward a wall (wall_faces).
struct WallFace {
  std::int64_t column = 0;  ///< the cell column along the wall's tangent axes holding the point [-]
  std::int64_t p = 0;       ///< the point [-]
  double dist = 0;          ///< the face's distance from the wall (distance minus extent) [m]
  double ext = 0;           ///< the domain's extent along the wall's normal [m]
};

/// The faces toward `wall` at time t [s] of the points [begin, end) whose face is within `range`
/// [m] of it, sorted by (column, dist, point); columns are the cells of size h [m] of the points'
/// centres projected on the wall's tangent axes.
template <int Dim>
std::vector<WallFace> wall_faces(const walls::Wall<Dim>& wall, double t,
                                 const DomainsView<Dim>& pts, std::int64_t begin, std::int64_t end,
                                 double range, double h);

/// The surface of the column starting at faces[f0] (wall_faces' order): its points whose face is
/// within half a domain's extent of the column's nearest (written to `surface`); returns the
/// index of the next column's first face [-].
std::size_t column_surface(std::span<const WallFace> faces, std::size_t f0,
                           std::vector<std::int64_t>& surface);

/// A grain's node box on the grid (the nodes lo + [0, n) in grid coordinates) and its active
/// nodes (nodes carrying mass).
template <int Dim>
struct NodeBoxView {
  Vec<Dim> origin = Vec<Dim>::Zero();           ///< position of grid node 0 [m]
  double h = 0;                                 ///< cell size [m]
  IVec<Dim> lo = IVec<Dim>::Zero();             ///< first node of the box (grid coordinates) [-]
  IVec<Dim> n = IVec<Dim>::Zero();              ///< nodes of the box per axis [-]
  std::span<const std::int32_t> box_to_active;  ///< box node (x fastest) -> active node, -1 [-]
};

/// Linear hat weights of the positions `corners` [m] at the box's active nodes, `weight` [-] each
/// position, normalised to a sum of 1 (a node without mass gives its share to the others): the
/// active nodes in order of first appearance and their weights; false if no active node carries
/// any weight.
template <int Dim>
bool corner_weights(const NodeBoxView<Dim>& box, std::span<const Vec<Dim>> corners, double weight,
                    std::vector<std::int32_t>& nodes, std::vector<double>& weights);

}  // namespace mpmcd::contact
