// Grain-grain face contacts whose normals follow the faces through the step
// (ContactSettings::face_normals_at_end; docs/contact.md, "Face normals at the end of the step"):
// each Newton iteration takes every face contact's normal from its face at the iterate's F^{n+1}
// and puts the symmetric part of that normal's derivative, the interface pressure's geometric
// stiffness, into the face grain's Newton matrix.
#include <algorithm>
#include <vector>

#include "mpmcd/contact/geometry.hpp"
#include "solver_detail.hpp"

namespace mpmcd::mpm {

template <int Dim>
void ImplicitSolver<Dim>::prepare_face_normals() {
  face_normals_.clear();
  face_blocks_.clear();
  face_start_.assign(work_.size() + 1, 0);
  for (auto& w : work_) w->follower_K.clear();
  const ContactSettings<Dim>& cs = settings_.contact;
  if (!cs.grain_faces || !cs.face_normals_at_end || distributed()) return;
  // The grain-grain face contacts: slot a is the face's grain X (a face slot), slot b the other
  // grain's, keyed -1 - (p 2 Dim + 2 axis + side) by grain_face_contacts.
  std::vector<std::int32_t> order;
  for (std::size_t c = 0; c < problem_.contacts.size(); ++c) {
    const contact::Contact<Dim>& k = problem_.contacts[c];
    if (k.a < 0 || !slot_is_face_[k.a] || !slot_is_face_[k.b] || slot_key_[k.b] >= 0) continue;
    order.push_back(static_cast<std::int32_t>(c));
    ++face_start_[static_cast<std::size_t>(slot_ref_[k.a].first) + 1];
  }
  for (std::size_t g = 0; g < work_.size(); ++g) face_start_[g + 1] += face_start_[g];
  // By grain (stable: contact order within a grain), so that the grains fill their blocks on the
  // threads in a fixed order.
  std::stable_sort(order.begin(), order.end(), [&](std::int32_t x, std::int32_t y) {
    return slot_ref_[problem_.contacts[x].a].first < slot_ref_[problem_.contacts[y].a].first;
  });
  for (const std::int32_t c : order) {
    const contact::Contact<Dim>& k = problem_.contacts[static_cast<std::size_t>(c)];
    const std::int64_t code = -1 - slot_key_[k.b];
    FaceNormal f;
    f.contact = c;
    f.point = code / (2 * Dim);
    f.axis = static_cast<int>(code % (2 * Dim)) / 2;
    f.sign = code % 2 ? 1.0 : -1.0;
    f.first_block = static_cast<std::int32_t>(face_blocks_.size());
    // Blocks (I, J): I a node of the face slot, J a node of the point's shape window. Both lie
    // in the window (the face's corners are corners of the point's domain), whose pair table
    // gives the stencil slot; a node outside it (a domain shrunk to fit the CPDI window) is
    // looked up in I's stencil row.
    const std::size_t g = static_cast<std::size_t>(slot_ref_[k.a].first);
    const GrainWork& w = *work_[g];
    const std::int64_t i = f.point - grains_[g].begin;
    const int K = w.K, S = w.S;
    const auto stencil_index = [&](std::int32_t I, std::int32_t J) -> std::int64_t {
      for (int s = 0; s < S; ++s)
        if (w.stencil_nb[static_cast<std::size_t>(I) * S + s] == J)
          return static_cast<std::int64_t>(I) * S + s;
      return -1;
    };
    for (std::int32_t q = slot_start_[k.a]; q < slot_start_[k.a + 1]; ++q) {
      const std::int32_t I = slot_node_[q];
      int aI = -1;
      for (int a = 0; a < K && aI < 0; ++a)
        if (w.pt_node[i * K + a] == I) aI = a;
      for (int a = 0; a < K; ++a) {
        const std::int32_t J = w.pt_node[i * K + a];
        if (J < 0) continue;
        std::int64_t ij = -1, ji = -1;
        if (aI >= 0) {
          ij = static_cast<std::int64_t>(I) * S + w.pair_slot[aI * K + a];
          ji = static_cast<std::int64_t>(J) * S + w.pair_slot[a * K + aI];
        }
        if (ij < 0 || w.stencil_nb[ij] != J) ij = stencil_index(I, J);
        if (ji < 0 || w.stencil_nb[ji] != I) ji = stencil_index(J, I);
        if (ij < 0 || ji < 0) continue;  // outside the stencil: the term is left out
        face_blocks_.push_back({q, a, ij, ji});
      }
    }
    f.end_block = static_cast<std::int32_t>(face_blocks_.size());
    face_normals_.push_back(f);
  }
}

template <int Dim>
void ImplicitSolver<Dim>::follow_face_normals() {
  if (face_normals_.empty()) return;
  ScopedStage stage(&timers_, "contact.follow");
  // 1. Each face contact's normal from its face at the iterate's F^{n+1} (face_normal, as the
  // detection takes it at F^n); its normal impulse turned with it, a tangential part kept
  // tangential. The gap, slots and weights stay those of the detection.
  // When no normal turns by more than contact.impulse_tolerance (radians), the impulses they
  // would turn change by less than the staggering's tolerance: the normals are left as they are
  // (so that a converging step does not iterate on round-off).
  const auto nf = static_cast<std::int64_t>(face_normals_.size());
  const bool threads = nf > 512;
  follow_normal_.resize(face_normals_.size());
  double turn = 0;
  {
    const ThreadedRegion threaded(&timers_, threads);
#pragma omp parallel for schedule(static) if (threads) reduction(max : turn)
    for (std::int64_t fi = 0; fi < nf; ++fi) {
      const FaceNormal& f = face_normals_[static_cast<std::size_t>(fi)];
      const contact::Contact<Dim>& c = problem_.contacts[static_cast<std::size_t>(f.contact)];
      const Vec<Dim> n =
          contact::face_normal<Dim>(trial_.F[f.point] * points_.domain[f.point], f.axis, f.sign);
      follow_normal_[static_cast<std::size_t>(fi)] = n;
      turn = std::max(turn, (n - c.normal).norm());
    }
  }
  if (turn > settings_.contact.impulse_tolerance) {
    for (std::int64_t fi = 0; fi < nf; ++fi) {
      const FaceNormal& f = face_normals_[static_cast<std::size_t>(fi)];
      contact::Contact<Dim>& c = problem_.contacts[static_cast<std::size_t>(f.contact)];
      const Vec<Dim>& n = follow_normal_[static_cast<std::size_t>(fi)];
      const double pn = c.impulse.dot(c.normal);
      const Vec<Dim> pt = c.impulse - pn * c.normal;
      c.normal = n;
      c.impulse = pn * n + (pt - n.dot(pt) * n);
    }
    follow_impulses();
  }
  follow_stiffness();
}

template <int Dim>
void ImplicitSolver<Dim>::follow_impulses() {
  // 2. The slots' and grains' impulses, and the residuals of the grains that have slots (their
  // F has not changed): the caller judges those it has just evaluated; a converged grain whose
  // impulses changed is reopened by the contact solve's response (impulses_changed).
  slot_P_ = contact::net_impulses(problem_);
  spread_slot_impulses();
  on_live_grains([&](std::size_t, GrainWork& w) {
    if (!w.slots.empty()) nodal_residual(w, settings_, dt_);
  });
}

template <int Dim>
template <class Fn>
void ImplicitSolver<Dim>::on_live_grains(Fn&& fn) {
  const auto ng = static_cast<std::int64_t>(work_.size());
  const ThreadedRegion threaded(&timers_, ng > 1);
#pragma omp parallel for schedule(dynamic, 1) if (ng > 1)
  for (std::int64_t gi = 0; gi < ng; ++gi) {
    const auto g = static_cast<std::size_t>(gi);
    GrainWork& w = *work_[g];
    if (role_[g] == 1 && w.failure.empty()) fn(g, w);
  }
}

template <int Dim>
void ImplicitSolver<Dim>::follow_stiffness() {
  const double dt = dt_;
  on_live_grains([&](std::size_t g, GrainWork& w) {
    // 3. The normal's stiffness: the face's impulse -p n on grain X at its slot's nodes I
    // (weights w_I) turns with the face, dn = -(I - n n^T) g_J (n . du_J) for du_J = theta dt
    // dv_J (face_normal_derivative), so the residual's derivative (method.md §2) gains
    // B_IJ = -theta dt p w_I (I - n n^T) g_J n^T, i.e. K_IJ += B_IJ / (theta^2 dt^2). The
    // per-grain factorisations take its symmetric part (B_IJ + B_JI^T) / 2; the reaction on the
    // other grain, and the unsymmetric rest, are left to the staggered iterations
    // (docs/contact.md).
    const std::int32_t f0 = face_start_[g], f1 = face_start_[g + 1];
    if (f0 == f1) return;
    w.follower_K.assign(w.K_blk.size(), Mat<Dim>::Zero());
    const double scale = 0.5 / (settings_.theta * dt);
    const std::int64_t begin = grains_[g].begin;
    for (std::int32_t k = f0; k < f1; ++k) {
      const FaceNormal& f = face_normals_[static_cast<std::size_t>(k)];
      const contact::Contact<Dim>& c = problem_.contacts[static_cast<std::size_t>(f.contact)];
      const double pn = c.impulse.dot(c.normal);
      if (!(pn > 0.0)) continue;
      const std::int64_t i = f.point - begin;
      const Mat<Dim>& dFinvT = trial_.dF_inv_T[f.point];
      for (std::int32_t b = f.first_block; b < f.end_block; ++b) {
        const FaceBlock& fb = face_blocks_[static_cast<std::size_t>(b)];
        const Vec<Dim> gJ = dFinvT * w.pt_dN[i * w.K + fb.a];
        const Mat<Dim> B =
            (scale * pn * slot_weight_[fb.q]) * contact::face_normal_derivative<Dim>(c.normal, gJ);
        w.follower_K[static_cast<std::size_t>(fb.ij)] += B;
        w.follower_K[static_cast<std::size_t>(fb.ji)] += B.transpose();
      }
    }
  });
}

// The members defined here (the class is instantiated in solver.cpp).
#define MPMCD_INSTANTIATE(D)                               \
  template void ImplicitSolver<D>::prepare_face_normals(); \
  template void ImplicitSolver<D>::follow_face_normals();  \
  template void ImplicitSolver<D>::follow_impulses();      \
  template void ImplicitSolver<D>::follow_stiffness();
MPMCD_INSTANTIATE(2)
MPMCD_INSTANTIATE(3)
#undef MPMCD_INSTANTIATE

}  // namespace mpmcd::mpm
