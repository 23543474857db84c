// Each registered law's tangent (a test's own laws included, test_law_recipe.cpp) is checked
// against central finite differences of P = J sigma F^-T, and the Neo-Hookean stress against the
// closed forms of method.md §7.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "mpmcd/core/errors.hpp"
#include "mpmcd/materials/law.hpp"

using namespace mpmcd;
using materials::LawBatch;

namespace {

template <int Dim>
Mat<Dim> stress(const materials::Law<Dim>& law, const Mat<Dim>& F, double* energy = nullptr) {
  Mat<Dim> sigma;
  double w = 0;
  LawBatch<Dim> b{{&F, 1}, {}, {}, {&sigma, 1}, {}, {&w, 1}, {}};
  law.evaluate(b);
  if (energy) *energy = w;
  return sigma;
}

template <int Dim>
Mat<Dim> first_piola(const materials::Law<Dim>& law, const Mat<Dim>& F) {
  return F.determinant() * stress(law, F) * F.inverse().transpose();
}

// a_ijkl = J^-1 F_jJ F_lL dP_iJ/dF_kL by central differences.
template <int Dim>
Tensor4<Dim> fd_tangent(const materials::Law<Dim>& law, const Mat<Dim>& F, double eps) {
  Tensor4<Dim> A;  // dP_iJ/dF_kL
  for (int k = 0; k < Dim; ++k)
    for (int L = 0; L < Dim; ++L) {
      Mat<Dim> Fp = F, Fm = F;
      Fp(k, L) += eps;
      Fm(k, L) -= eps;
      const Mat<Dim> dP = (first_piola(law, Fp) - first_piola(law, Fm)) / (2 * eps);
      for (int i = 0; i < Dim; ++i)
        for (int J = 0; J < Dim; ++J) A(i * Dim + J, k * Dim + L) = dP(i, J);
    }
  Tensor4<Dim> a = Tensor4<Dim>::Zero();
  const double detF = F.determinant();
  for (int i = 0; i < Dim; ++i)
    for (int j = 0; j < Dim; ++j)
      for (int k = 0; k < Dim; ++k)
        for (int l = 0; l < Dim; ++l)
          for (int J = 0; J < Dim; ++J)
            for (int L = 0; L < Dim; ++L)
              a(i * Dim + j, k * Dim + l) += F(j, J) * F(l, L) * A(i * Dim + J, k * Dim + L) / detF;
  return a;
}

// Values for the parameters of any registered law: 3e6, 1.5e6, 1e6, ... [Pa] in the order of its
// ParamSpecs (lambda = 3 MPa, mu = 1.5 MPa for the laws of lambda and mu).
materials::LawParams some_params(const materials::LawInfo& info) {
  materials::LawParams params;
  for (std::size_t k = 0; k < info.params.size(); ++k)
    params[info.params[k].name] =
        std::clamp(3e6 / static_cast<double>(k + 1), info.params[k].min, info.params[k].max);
  return params;
}

template <int Dim>
void check_tangent(const materials::LawInfo& info) {
  const std::string& name = info.name;
  auto law = materials::make_law<Dim>(name, some_params(info));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int trial = 0; trial < 20; ++trial) {
    Mat<Dim> F = Mat<Dim>::Identity();
    for (int i = 0; i < Dim; ++i)
      for (int j = 0; j < Dim; ++j) F(i, j) += u(rng);
    if (F.determinant() < 0.3) continue;
    Mat<Dim> sigma;
    Tensor4<Dim> a;
    LawBatch<Dim> b{{&F, 1}, {}, {}, {&sigma, 1}, {&a, 1}, {}, {}};
    law->evaluate(b);
    const Tensor4<Dim> a_fd = fd_tangent(*law, F, 1e-6);
    const double err = (a - a_fd).norm() / a_fd.norm();
    EXPECT_LT(err, 1e-7) << name << " Dim=" << Dim << " trial " << trial << "\nF=\n"
                         << F << "\na=\n"
                         << a << "\nfd=\n"
                         << a_fd;
    if (law->symmetric_tangent()) {
      EXPECT_LT((a - a.transpose()).norm() / a.norm(), 1e-12);
    }
  }
}

// Energy consistency: dW/dF = P (hyperelastic laws).
template <int Dim>
void check_energy(const std::string& name) {
  auto law = materials::make_law<Dim>(name, {{"lambda", 3e6}, {"mu", 1.5e6}});
  Mat<Dim> F = Mat<Dim>::Identity();
  F(0, 0) = 0.9;
  F(0, 1) = 0.2;
  F(1, 0) = -0.05;
  const Mat<Dim> P = first_piola(*law, F);
  for (int k = 0; k < Dim; ++k)
    for (int L = 0; L < Dim; ++L) {
      Mat<Dim> Fp = F, Fm = F;
      const double h = 1e-6;
      Fp(k, L) += h;
      Fm(k, L) -= h;
      double wp, wm;
      stress(*law, Fp, &wp);
      stress(*law, Fm, &wm);
      EXPECT_NEAR((wp - wm) / (2 * h), P(k, L), 1e-6 * P.norm()) << name << " " << k << L;
    }
}

}  // namespace

TEST(Laws, TangentsMatchFiniteDifferences2D) {
  for (const auto& info : materials::law_registry()) check_tangent<2>(info);
}

TEST(Laws, TangentsMatchFiniteDifferences3D) {
  for (const auto& info : materials::law_registry()) check_tangent<3>(info);
}

TEST(Laws, HyperelasticEnergyDerivativeIsFirstPiola) {
  check_energy<2>("neo_hookean");
  check_energy<2>("saint_venant_kirchhoff");
  check_energy<3>("neo_hookean");
  check_energy<3>("saint_venant_kirchhoff");
}

TEST(Laws, NeoHookeanClosedFormsOfMethod7) {
  auto law = materials::make_law<2>("neo_hookean", {{"lambda", 3e6}, {"mu", 1.5e6}});
  // Confined compression F = diag(1, 0.9): sigma22 = -0.66787 MPa, sigma11 = -0.35120 MPa.
  Mat<2> F = Mat<2>::Identity();
  F(1, 1) = 0.9;
  Mat<2> s = stress(*law, F);
  const double s22 = (1.5e6 * (0.81 - 1) + 3e6 * std::log(0.9)) / 0.9;
  const double s11 = 3e6 * std::log(0.9) / 0.9;
  EXPECT_NEAR(s(1, 1), s22, 1e-8 * std::abs(s22));
  EXPECT_NEAR(s(0, 0), s11, 1e-8 * std::abs(s11));
  EXPECT_NEAR(s22 / 1e6, -0.66787, 5e-6);
  EXPECT_NEAR(s11 / 1e6, -0.35120, 5e-6);
  // Simple shear: sigma12 = mu gamma, sigma11 = mu gamma^2, sigma22 = 0.
  F = Mat<2>::Identity();
  F(0, 1) = 0.4;
  s = stress(*law, F);
  EXPECT_NEAR(s(0, 1), 1.5e6 * 0.4, 1e-9 * 1.5e6);
  EXPECT_NEAR(s(0, 0), 1.5e6 * 0.16, 1e-9 * 1.5e6);
  EXPECT_NEAR(s(1, 1), 0.0, 1e-9 * 1.5e6);
}

TEST(Laws, RegistryRejectsUnknownLawAndBadParameters) {
  EXPECT_THROW(materials::make_law<2>("rubber", {{"lambda", 1}, {"mu", 1}}), InputError);
  EXPECT_THROW(materials::make_law<2>("neo_hookean", {{"mu", 1}}), InputError);
  EXPECT_THROW(materials::make_law<2>("neo_hookean", {{"lambda", 1}, {"mu", -1}}), InputError);
  EXPECT_THROW(materials::make_law<2>("neo_hookean", {{"lambda", 1}, {"mu", 1}, {"nu", 0.3}}),
               InputError);
}
