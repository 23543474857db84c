// The geometry of contact detection (contact/geometry.hpp) on hand-made domains: extents and
// reaches, the face of a sheared or rotated domain toward a wall, gaps of known domains, ray
// entries, a grain node near a wall, the faces of a block facing a wall, and the hat weights of
// face corners (partition of unity, linear fields).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "mpmcd/contact/geometry.hpp"

using namespace mpmcd;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A plane wall through `point` with unit `normal` (into the domain), at rest.
template <int Dim>
walls::Wall<Dim> wall_at(const Vec<Dim>& point, const Vec<Dim>& normal) {
  walls::Wall<Dim> w;
  w.point = point;
  w.normal = normal;
  return w;
}

// Points of domains x + F D0 s held in arrays, with their view.
template <int Dim>
struct Domains {
  std::vector<Vec<Dim>> x;
  std::vector<Mat<Dim>> F, D0;
  void add(const Vec<Dim>& xc, const Mat<Dim>& f, const Mat<Dim>& d0) {
    x.push_back(xc);
    F.push_back(f);
    D0.push_back(d0);
  }
  contact::DomainsView<Dim> view() const { return {x, F, D0}; }
};

}  // namespace

TEST(ContactGeometry, ExtentAndReachOfASquare) {
  const double lp = 0.25;
  const Mat<2> D0 = lp * Mat<2>::Identity();
  const Mat<2> I = Mat<2>::Identity();
  EXPECT_DOUBLE_EQ(contact::domain_extent<2>(I, D0, Vec<2>(1, 0)), lp);
  EXPECT_DOUBLE_EQ(contact::domain_extent<2>(I, D0, Vec<2>(0, -1)), lp);
  EXPECT_NEAR(contact::domain_extent<2>(I, D0, Vec<2>(1, 1).normalized()), lp * std::sqrt(2.0),
              1e-15);
  // Stretched by 2 along x: twice the extent along x, the same along y.
  Mat<2> F;
  F << 2, 0, 0, 1;
  EXPECT_DOUBLE_EQ(contact::domain_extent<2>(F, D0, Vec<2>(1, 0)), 2 * lp);
  EXPECT_DOUBLE_EQ(contact::domain_extent<2>(F, D0, Vec<2>(0, 1)), lp);
  EXPECT_DOUBLE_EQ(contact::domain_reach<2>(F * D0), 3 * lp);
  // The reach bounds the extent along any direction.
  for (int k = 0; k < 16; ++k) {
    const double a = k * std::numbers::pi / 8;
    const Vec<2> n(std::cos(a), std::sin(a));
    EXPECT_LE(contact::domain_extent<2>(F, D0, n), contact::domain_reach<2>(F * D0) + 1e-15);
  }
  EXPECT_DOUBLE_EQ(contact::domain_reach<3>(lp * Mat<3>::Identity()), 3 * lp);
}

TEST(ContactGeometry, FaceOfAShearedDomainTowardAWall) {
  // A square of half-edge 1 sheared along x (columns (1, 0) and (0.3, 1)) above a floor (normal
  // +y into the domain): the face toward it is the bottom one, s_y = -1, both its corners.
  Mat<2> D;
  D << 1, 0.3, 0, 1;
  const Vec<2> x(2, 5);
  std::vector<Vec<2>> corners;
  const Vec<2> c = contact::face_toward<2>(x, D, Vec<2>(0, 1), corners);
  EXPECT_TRUE(c.isApprox(Vec<2>(1.7, 4)));
  ASSERT_EQ(corners.size(), 2u);
  EXPECT_TRUE(corners[0].isApprox(Vec<2>(0.7, 4)));  // s = (-1, -1)
  EXPECT_TRUE(corners[1].isApprox(Vec<2>(2.7, 4)));  // s = (+1, -1)
  // A left wall (normal +x): the face s_x = -1, although its corners are not the leftmost
  // points of the sheared domain (the most nearly parallel face normal, not the nearest corner).
  corners.clear();
  const Vec<2> cl = contact::face_toward<2>(x, D, Vec<2>(1, 0), corners);
  EXPECT_TRUE(cl.isApprox(x - D.col(0)));
  ASSERT_EQ(corners.size(), 2u);
  EXPECT_TRUE(corners[0].isApprox(x - D.col(0) - D.col(1)));
  EXPECT_TRUE(corners[1].isApprox(x - D.col(0) + D.col(1)));
  // A ceiling (normal -y): the top face.
  corners.clear();
  EXPECT_TRUE(contact::face_toward<2>(x, D, Vec<2>(0, -1), corners).isApprox(x + D.col(1)));
  // 3D: a cube rotated by 0.2 rad about z over a floor of normal +z: the face s_z = -1 with its
  // four corners, appended after the ones already there.
  const double a = 0.2;
  Mat<3> R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  const Mat<3> D3 = 0.5 * R;
  const Vec<3> x3(1, 1, 1);
  std::vector<Vec<3>> c3(1, Vec<3>::Zero());
  EXPECT_TRUE(contact::face_toward<3>(x3, D3, Vec<3>(0, 0, 1), c3).isApprox(Vec<3>(1, 1, 0.5)));
  ASSERT_EQ(c3.size(), 5u);
  for (int k = 1; k < 5; ++k) EXPECT_DOUBLE_EQ(c3[k][2], 0.5);
  EXPECT_TRUE(c3[1].isApprox(x3 + D3 * Vec<3>(-1, -1, -1)));
  EXPECT_TRUE(c3[4].isApprox(x3 + D3 * Vec<3>(1, 1, -1)));
}

TEST(ContactGeometry, GapOfTwoKnownDomains) {
  const double lp = 0.5;
  Domains<2> d;
  const Mat<2> I = Mat<2>::Identity(), D0 = lp * I;
  d.add(Vec<2>(0, 0), I, D0);
  d.add(Vec<2>(3 * lp, 0), I, D0);       // side by side, lp apart
  d.add(Vec<2>(3 * lp, 3 * lp), I, D0);  // diagonal: corners sqrt(2) lp apart on the line
  d.add(Vec<2>(1.5 * lp, 0), I, D0);     // overlapping the first by lp / 2
  d.add(Vec<2>(0, 0), I, D0);            // coincident with the first
  const auto v = d.view();
  EXPECT_NEAR(contact::pair_gap<2>(v, 0, 1), lp, 1e-15);
  EXPECT_NEAR(contact::pair_gap<2>(v, 1, 0), lp, 1e-15);
  EXPECT_NEAR(contact::pair_gap<2>(v, 0, 2), std::sqrt(2.0) * lp, 1e-15);
  EXPECT_NEAR(contact::pair_gap<2>(v, 0, 3), -0.5 * lp, 1e-15);
  // The nearest pair of two sets, with their reaches (2 lp each).
  const std::vector<double> reach(5, 2 * lp);
  const std::vector<std::int32_t> first{0}, far{1, 2}, all{1, 2, 3}, same{4};
  EXPECT_NEAR(contact::nearest_gap<2>(v, reach, 0, first, 0, far), lp, 1e-15);
  EXPECT_NEAR(contact::nearest_gap<2>(v, reach, 0, first, 0, all), -0.5 * lp, 1e-15);
  EXPECT_EQ(contact::nearest_gap<2>(v, reach, 0, first, 0, same), 0.0);
  EXPECT_EQ(contact::nearest_gap<2>(v, reach, 0, first, 0, {}), kInf);
  // Offsets: the sets are offsets from a grain's first point.
  const std::vector<std::int32_t> zero{0}, one{1};
  EXPECT_NEAR(contact::nearest_gap<2>(v, reach, 0, zero, 1, one), std::sqrt(2.0) * lp, 1e-15);
}

TEST(ContactGeometry, RayEntryIntoADomain) {
  // The square [-1, 1]^2 stretched to [-2, 2] x [-1, 1]: D = diag(2, 1).
  Mat<2> D;
  D << 2, 0, 0, 1;
  const Mat<2> Dinv = D.inverse();
  const Vec<2> xq(0, 0);
  EXPECT_DOUBLE_EQ(contact::ray_entry<2>(xq, Dinv, Vec<2>(-5, 0), Vec<2>(1, 0)), 3.0);
  EXPECT_DOUBLE_EQ(contact::ray_entry<2>(xq, Dinv, Vec<2>(0, 4), Vec<2>(0, -1)), 3.0);
  EXPECT_NEAR(contact::ray_entry<2>(xq, Dinv, Vec<2>(-3, -1.5), Vec<2>(1, 1).normalized()),
              std::sqrt(2.0), 1e-15);  // enters through x = -2 at y = -0.5
  EXPECT_EQ(contact::ray_entry<2>(xq, Dinv, Vec<2>(-5, 2), Vec<2>(1, 0)), kInf);        // misses
  EXPECT_EQ(contact::ray_entry<2>(xq, Dinv, Vec<2>(5, 0), Vec<2>(1, 0)), kInf);         // behind
  EXPECT_DOUBLE_EQ(contact::ray_entry<2>(xq, Dinv, Vec<2>(1, 0), Vec<2>(1, 0)), -3.0);  // inside
}

TEST(ContactGeometry, GrainNodeNearAWall) {
  const double lp = 0.25;
  const auto floor = wall_at<2>(Vec<2>(0, 0), Vec<2>(0, 1));
  Domains<2> d;
  const Mat<2> I = Mat<2>::Identity();
  d.add(Vec<2>(1, 2 * lp), I, lp * I);  // bottom face lp above the floor
  d.add(Vec<2>(1, 4 * lp), I, lp * I);  // 3 lp above
  const std::vector<std::int32_t> both{0, 1}, top{1}, none{};
  // A node below the points: their nearest face.
  EXPECT_NEAR(contact::node_wall_gap<2>(floor, 0.0, Vec<2>(1, 0.5 * lp), d.view(), 0, both), lp,
              1e-15);
  // A node deep inside: its distance minus one whole domain (2 lp).
  EXPECT_NEAR(contact::node_wall_gap<2>(floor, 0.0, Vec<2>(1, 6 * lp), d.view(), 0, top), 4 * lp,
              1e-15);
  EXPECT_EQ(contact::node_wall_gap<2>(floor, 0.0, Vec<2>(1, lp), d.view(), 0, none), kInf);
  // The wall moving up at 1 m/s: 0.1 s later everything is 0.1 m nearer.
  auto moving = floor;
  moving.velocity = Vec<2>(0, 1);
  EXPECT_NEAR(contact::node_wall_gap<2>(moving, 0.1, Vec<2>(1, 0.5 * lp), d.view(), 0, both),
              lp - 0.1, 1e-15);
}

TEST(ContactGeometry, FacesOfABlockTowardAWall) {
  // Squares of half-edge 0.25 above a floor, in three columns (cells of h = 1): the left one
  // with four faces, of which 0.1 and 0.15 are within half an extent (0.125) of the nearest (the
  // column's surface) and 0.25 and 0.6 are not; one face beyond the range.
  const double lp = 0.25, h = 1.0;
  const auto floor = wall_at<2>(Vec<2>(0, 0), Vec<2>(0, 1));
  Domains<2> d;
  const Mat<2> I = Mat<2>::Identity(), D0 = lp * I;
  d.add(Vec<2>(0.5, 0.35), I, D0);  // 0: column 0, face at 0.1
  d.add(Vec<2>(0.5, 0.85), I, D0);  // 1: column 0, above 0: face at 0.6
  d.add(Vec<2>(1.5, 0.55), I, D0);  // 2: column 1, face at 0.3
  d.add(Vec<2>(1.5, 1.05), I, D0);  // 3: column 1, face at 0.8
  d.add(Vec<2>(2.5, 0.35), I, D0);  // 4: column 2, face at 0.1
  d.add(Vec<2>(0.7, 0.50), I, D0);  // 5: column 0, face at 0.25 (not within 0.125 of 0.1)
  d.add(Vec<2>(0.3, 0.40), I, D0);  // 6: column 0, face at 0.15 (within 0.125 of 0.1)
  const auto faces = contact::wall_faces<2>(floor, 0.0, d.view(), 0, 7, 0.7, h);
  // Point 3's face (0.8) is beyond the range 0.7; the rest sorted by column then distance.
  ASSERT_EQ(faces.size(), 6u);
  const std::vector<std::int64_t> order{0, 6, 5, 1, 2, 4};
  for (std::size_t k = 0; k < order.size(); ++k) EXPECT_EQ(faces[k].p, order[k]) << k;
  EXPECT_NEAR(faces[0].dist, 0.1, 1e-15);
  EXPECT_DOUBLE_EQ(faces[0].ext, lp);
  std::vector<std::int64_t> surface;
  std::size_t f = contact::column_surface(faces, 0, surface);
  EXPECT_EQ(f, 4u);
  EXPECT_EQ(surface, (std::vector<std::int64_t>{0, 6}));
  f = contact::column_surface(faces, f, surface);
  EXPECT_EQ(f, 5u);
  EXPECT_EQ(surface, (std::vector<std::int64_t>{2}));
  f = contact::column_surface(faces, f, surface);
  EXPECT_EQ(f, 6u);
  EXPECT_EQ(surface, (std::vector<std::int64_t>{4}));
}

TEST(ContactGeometry, CornerWeightsPartitionOfUnity) {
  // A 4 x 3 node box from grid node (1, 2), h = 0.5, origin (-1, -1); all nodes active except
  // box node (2, 1).
  contact::NodeBoxView<2> box;
  box.origin = Vec<2>(-1, -1);
  box.h = 0.5;
  box.lo = IVec<2>(1, 2);
  box.n = IVec<2>(4, 3);
  std::vector<std::int32_t> active(12);
  for (std::int32_t k = 0, a = 0; k < 12; ++k) active[k] = k == 2 + 4 * 1 ? -1 : a++;
  box.box_to_active = active;
  const auto node_x = [&](std::int32_t a) {  // position of active node a
    std::int32_t k = 0;
    while (active[k] != a) ++k;
    const Vec<2> c(static_cast<double>(box.lo[0] + k % 4), static_cast<double>(box.lo[1] + k / 4));
    return Vec<2>(box.origin + box.h * c);
  };
  std::vector<std::int32_t> nodes;
  std::vector<double> weights;
  // Two corners in cells whose nodes all carry mass: the weights sum to 1 and interpolate a
  // linear field to its mean at the corners.
  const std::vector<Vec<2>> corners{Vec<2>(-0.4, 0.1), Vec<2>(-0.15, 0.3)};
  ASSERT_TRUE(contact::corner_weights<2>(box, corners, 0.5, nodes, weights));
  EXPECT_EQ(nodes.size(), weights.size());
  double sum = 0;
  Vec<2> mean = Vec<2>::Zero();
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    sum += weights[k];
    mean += weights[k] * node_x(nodes[k]);
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_TRUE(mean.isApprox(0.5 * (corners[0] + corners[1]), 1e-14));
  for (std::size_t k = 0; k < nodes.size(); ++k)
    for (std::size_t j = k + 1; j < nodes.size(); ++j) EXPECT_NE(nodes[k], nodes[j]);
  // A corner next to the node without mass: its share goes to the others, still a sum of 1.
  const std::vector<Vec<2>> near_empty{Vec<2>(0.4, 0.1)};
  ASSERT_TRUE(contact::corner_weights<2>(box, near_empty, 1.0, nodes, weights));
  EXPECT_EQ(nodes.size(), 3u);
  sum = 0;
  for (const double w : weights) sum += w;
  EXPECT_NEAR(sum, 1.0, 1e-15);
  // A corner on a node: that node alone.
  const std::vector<Vec<2>> on_node{node_x(0)};
  ASSERT_TRUE(contact::corner_weights<2>(box, on_node, 1.0, nodes, weights));
  EXPECT_EQ(nodes, (std::vector<std::int32_t>{0}));
  EXPECT_EQ(weights, (std::vector<double>{1.0}));
  // Far outside the box: no active node, false.
  const std::vector<Vec<2>> outside{Vec<2>(5, 5)};
  EXPECT_FALSE(contact::corner_weights<2>(box, outside, 1.0, nodes, weights));
}

TEST(ContactGeometry, CornerWeightsOfAFaceIn3D) {
  // The four corners of a cube's face inside a 3 x 3 x 3 box of active nodes (h = 1): the
  // weights sum to 1 and interpolate positions to the face centre.
  contact::NodeBoxView<3> box;
  box.h = 1.0;
  box.n = IVec<3>(3, 3, 3);
  std::vector<std::int32_t> active(27);
  for (std::int32_t k = 0; k < 27; ++k) active[k] = k;
  box.box_to_active = active;
  std::vector<Vec<3>> corners;
  contact::face_corners<3>(Vec<3>(1.1, 0.9, 1.3), 0.3 * Mat<3>::Identity(), 2, -1.0, corners);
  ASSERT_EQ(corners.size(), 4u);
  std::vector<std::int32_t> nodes;
  std::vector<double> weights;
  ASSERT_TRUE(contact::corner_weights<3>(box, corners, 0.25, nodes, weights));
  double sum = 0;
  Vec<3> mean = Vec<3>::Zero();
  for (std::size_t k = 0; k < nodes.size(); ++k) {
    sum += weights[k];
    const std::int32_t a = nodes[k];
    mean += weights[k] * Vec<3>(a % 3, (a / 3) % 3, a / 9);
  }
  EXPECT_NEAR(sum, 1.0, 1e-15);
  EXPECT_TRUE(mean.isApprox(Vec<3>(1.1, 0.9, 1.0), 1e-14));
}

// The derivative of a face's normal as the domain moves with dF = I + du (x) grad N (one node),
// against central differences of face_normal, on a sheared and stretched domain, every face, in
// 2D and 3D. Seen: agreement to 1e-9 (the differences' own error at step 1e-6).
template <int Dim>
void check_face_normal_derivative() {
  Mat<Dim> Fn = Mat<Dim>::Identity(), D0 = Mat<Dim>::Identity() * 2.5e-5;
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j) Fn(i, j) += 0.1 * (i + 1) * (j == i ? -1.0 : 0.5) / (1 + i + j);
  D0(0, Dim - 1) = 4e-6;
  Vec<Dim> grad, du0;
  for (int d = 0; d < Dim; ++d) {
    grad[d] = (d % 2 ? -3.0e4 : 2.0e4) + 1e3 * d;  // grad N_J(x^n) [1/m]
    du0[d] = (d + 1) * 1e-7;                       // the node's increment so far [m]
  }
  const Mat<Dim> Dn = Fn * D0;
  const auto normal = [&](const Vec<Dim>& du, int axis, double sign) {
    const Mat<Dim> dF = Mat<Dim>::Identity() + du * grad.transpose();
    return contact::face_normal<Dim>(dF * Dn, axis, sign);
  };
  const Mat<Dim> dF0 = Mat<Dim>::Identity() + du0 * grad.transpose();
  const Vec<Dim> g = dF0.inverse().transpose() * grad;
  for (int axis = 0; axis < Dim; ++axis)
    for (const double sign : {-1.0, 1.0}) {
      const Vec<Dim> n = normal(du0, axis, sign);
      EXPECT_NEAR(n.norm(), 1.0, 1e-14);
      // Outward: the face centre lies at +sign D e_axis from the point, n points away from it.
      EXPECT_GT(n.dot(sign * (dF0 * Dn).col(axis)), 0.0);
      const Mat<Dim> analytic = contact::face_normal_derivative<Dim>(n, g);
      const double step = 1e-6 / grad.norm();
      for (int d = 0; d < Dim; ++d) {
        Vec<Dim> e = Vec<Dim>::Zero();
        e[d] = step;
        const Vec<Dim> numeric =
            (normal(du0 + e, axis, sign) - normal(du0 - e, axis, sign)) / (2 * step);
        for (int i = 0; i < Dim; ++i)
          EXPECT_NEAR(analytic(i, d), numeric[i], 1e-9 * grad.norm())
              << "Dim " << Dim << " axis " << axis << " sign " << sign << " (" << i << ", " << d
              << ")";
      }
    }
}

TEST(ContactGeometry, FaceNormalDerivativeMatchesDifferences) {
  check_face_normal_derivative<2>();
  check_face_normal_derivative<3>();
}
