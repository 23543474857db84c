#pragma once
/// The contact problem of one step as plain data (method.md §4), the default contact law's exact
/// local Signorini-Coulomb solver (other laws: contact/law.hpp), the nonlinear Gauss-Seidel over
/// all contacts, and the one error measure shared by the solver and the tests. It can be written
/// to a file and replayed.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "mpmcd/core/thread_tuner.hpp"
#include "mpmcd/core/timer.hpp"
#include "mpmcd/core/types.hpp"

namespace mpmcd::contact {

/// A grain-field node taking part in contacts.
template <int Dim>
struct Slot {
  double mass = 0;                     ///< nodal mass m_I of the grain field [kg]
  Vec<Dim> v_free = Vec<Dim>::Zero();  ///< end-of-step velocity without contact impulses [m/s]
  std::int32_t grain = -1;             ///< grain owning the field (information only)
  std::int64_t node = -1;              ///< global grid node (information only)
  std::int32_t group = -1;             ///< compliance group (-1: lumped response P / mass)
  std::int32_t local = -1;             ///< index of the slot in its group
};

/// The linearised response of one grain at its contact slots (the "stiffness-corrected" Delassus
/// operator of method.md §4): the velocity of slot i changes by sum_j G_ij P_j for net impulses
/// P_j on the group's slots, G = E^T A^-1 E with A the grain's Newton matrix. It is stored on the
/// slots' contact directions: the impulses on slot j lie in the span of the first rank(j) columns
/// of basis[j] (its frictionless contacts' normals, or all Dim directions), and
/// G_ij = B_i Gr_ij B_j^T with Gr = B^T G B (docs/contact.md, "Compliance on the contact
/// directions"). A frictionless face slot needs one number per slot pair instead of Dim^2.
template <int Dim>
struct Group {
  std::vector<std::int32_t> slots;  ///< slots of the group, in local order
  std::vector<Mat<Dim>> basis;  ///< per slot: orthonormal directions in its first rank columns [-]
  std::vector<Eigen::Index> col;  ///< per slot j: its first row of Gr; col[k] = Gr's size [-]
  Eigen::MatrixXd Gr;             ///< B^T G B, the compliance on the directions [s/kg]

  /// Number of directions of slot j (1 to Dim) [-].
  int rank(std::size_t j) const { return static_cast<int>(col[j + 1] - col[j]); }
  /// Block G_ij = B_i Gr_ij B_j^T: response of slot i's velocity to an impulse on slot j [s/kg].
  Mat<Dim> block(std::size_t i, std::size_t j) const {
    Mat<Dim> T = Mat<Dim>::Zero();  // B_i Gr_ij in its first rank(j) columns
    for (int n = 0; n < rank(j); ++n)
      for (int a = 0; a < Dim; ++a)
        for (int m = 0; m < rank(i); ++m) T(a, n) += basis[i](a, m) * Gr(col[i] + m, col[j] + n);
    Mat<Dim> out = Mat<Dim>::Zero();
    for (int b = 0; b < Dim; ++b)
      for (int a = 0; a < Dim; ++a)
        for (int n = 0; n < rank(j); ++n) out(a, b) += T(a, n) * basis[j](b, n);
    return out;
  }
  /// u_i . (G_ij w_j) = (B_i^T u_i) . Gr_ij (B_j^T w_j) for vectors u_i, w_j [s/kg].
  double bilinear(std::size_t i, const Vec<Dim>& u, std::size_t j, const Vec<Dim>& w) const {
    double acc = 0;
    for (int n = 0; n < rank(j); ++n) {
      double row = 0;
      for (int m = 0; m < rank(i); ++m) row += u.dot(basis[i].col(m)) * Gr(col[i] + m, col[j] + n);
      acc += row * basis[j].col(n).dot(w);
    }
    return acc;
  }
  /// Every slot with all Dim directions (B = I): Gr = G, a full (Dim k) x (Dim k) compliance
  /// [s/kg].
  void set_full(const Eigen::MatrixXd& G) {
    const auto k = slots.size();
    basis.assign(k, Mat<Dim>::Identity());
    col.resize(k + 1);
    for (std::size_t j = 0; j <= k; ++j) col[j] = static_cast<Eigen::Index>(Dim * j);
    Gr = G;
  }
  /// G expanded to (Dim k) x (Dim k), slot after slot [s/kg].
  Eigen::MatrixXd full() const {
    const auto k = static_cast<Eigen::Index>(slots.size());
    Eigen::MatrixXd G(Dim * k, Dim * k);
    for (Eigen::Index i = 0; i < k; ++i)
      for (Eigen::Index j = 0; j < k; ++j)
        G.template block<Dim, Dim>(Dim * i, Dim * j) =
            block(static_cast<std::size_t>(i), static_cast<std::size_t>(j));
    return G;
  }
};

/// One contact between slot A (or a wall, a = -1) and slot B; the impulse acts on B, its opposite
/// on A.
template <int Dim>
struct Contact {
  std::int32_t a = -1;                        ///< slot of body A, -1 for a wall (infinite mass)
  std::int32_t b = -1;                        ///< slot of body B
  std::int32_t wall = -1;                     ///< wall index when a = -1
  Vec<Dim> normal = Vec<Dim>::Zero();         ///< unit normal from A to B
  Vec<Dim> wall_velocity = Vec<Dim>::Zero();  ///< velocity of the wall when a = -1 [m/s]
  double gap = 0;                             ///< g+ >= 0: A and B may approach by g this step [m]
  double friction = 0;                        ///< Coulomb coefficient mu_f [-]
  Vec<Dim> impulse = Vec<Dim>::Zero();        ///< impulse on B over the step (in: warm start) [N s]
};

/// The whole problem of a step.
template <int Dim>
struct Problem {
  double dt = 0;  ///< time step [s]
  /// The contact law of every contact, by its registry name (contact/law.hpp): its local solver
  /// is looked up once per solve, not per contact.
  std::string law = "coulomb";
  std::vector<Slot<Dim>> slots;        ///< nodes taking part
  std::vector<Contact<Dim>> contacts;  ///< contacts (their impulses are the unknowns)
  std::vector<Group<Dim>> groups;      ///< compliance groups (empty: all slots lumped)
};

/// The order of a Gauss-Seidel sweep over a problem's contacts: the contacts grouped by the node
/// of their slot B, each node's in the serial order, as runs of `order` from start[r] to
/// start[r + 1]; the runs of one phase (runs phase[k] to phase[k + 1]) share no slot and no
/// compliance group, so they are swept on the threads, the phases one after the other. With the
/// lumped operator (no compliance group) a slot belongs to one node and responds to its own
/// impulses only: one phase of independent per-node runs (docs/parallel.md). When groups couple
/// the nodes, each node's contacts are a run and the runs are coloured greedily, in node order,
/// so that no two runs of a colour touch the same group or lumped slot (multicolour
/// Gauss-Seidel): one phase per colour. Either way the result does not depend on the thread
/// count. It depends only on the contacts' slots and the groups, not on the impulses.
struct SweepOrder {
  std::vector<std::int32_t> order;  ///< contact indices, run after run
  std::vector<std::int32_t> start;  ///< run r is order[start[r] .. start[r + 1])
  std::vector<std::int32_t> phase;  ///< phase k is runs phase[k] .. phase[k + 1]
};

/// Gauss-Seidel settings.
struct GsSettings {
  double tolerance = 1e-8;  ///< stop when error(problem) <= tolerance [-]
  int max_sweeps = 1000;    ///< sweep limit [-]
  /// Over-relaxation omega in [1, 2) of the frictionless contacts' local updates (projected
  /// SOR, Cryer 1971), from sweep relax_after on; frictional contacts keep omega = 1 [-].
  double relaxation = 1.0;
  int relax_after = 0;  ///< sweeps done with omega = 1 before the relaxation starts [-]
  /// Solve the frictionless contacts of each node (2 to 6) together, exactly (nodal block
  /// Gauss-Seidel), instead of one by one: near-redundant contacts at a node where a light field
  /// is pinched between two grains then cost one step, not thousands of sweeps.
  bool node_blocks = true;
  /// solve_active_set: block principal pivots per proximal step at most before the primal
  /// active-set method takes over from the last proximal iterate (it takes over earlier, from the
  /// last pivot, when the number of infeasible contacts stops falling; docs/contact.md) [-].
  int block_pivots = 100;
  /// Where the threaded sweeps and error sums add their time (ThreadedRegion); none if null.
  StageTimers* timers = nullptr;
  /// Chooses sweep by sweep between the threads and one thread from their measured cost (the
  /// same impulses either way: core/thread_tuner.hpp); null: the threads whenever the problem is
  /// large enough.
  ThreadTuner* tuner = nullptr;
  /// The problem's sweep order (sweep_order) when the caller keeps it for several solves of the
  /// same contacts and groups (the Newton iterations of a step); null: made by each solve.
  const SweepOrder* order = nullptr;
};

/// Gauss-Seidel outcome.
struct GsResult {
  int sweeps = 0;          ///< sweeps done
  int pivots = 0;          ///< active-set pivoting steps (solve_active_set) [-]
  double error = 0;        ///< final error(problem) [-]
  bool converged = false;  ///< error <= tolerance
};

/// The default contact law's ("coulomb", contact/law.hpp; src/contact/coulomb.cpp) local solver.
/// Exact solution of one contact's local problem u = u_free + W P with an SPD Delassus block W:
/// open if u_free.n + g/dt >= 0 without impulse, else stick (u_t = 0, u_n + g/dt = 0) if its
/// impulse lies in the Coulomb cone |p_t| <= mu p_n, else slide on the cone against the sliding
/// velocity (method.md §4). Exact in 2D for any W; in 3D exact for isotropic W = w I.
template <int Dim>
Vec<Dim> local_solution(const Vec<Dim>& u_free, const Mat<Dim>& W, const Vec<Dim>& n,
                        double gap_over_dt, double mu);

/// Lumped form W = w I of local_solution.
template <int Dim>
Vec<Dim> local_solution(const Vec<Dim>& u_free, double w, const Vec<Dim>& n, double gap_over_dt,
                        double mu) {
  return local_solution<Dim>(u_free, Mat<Dim>(w * Mat<Dim>::Identity()), n, gap_over_dt, mu);
}

/// Mean force of a contact over the step of length dt [s] from its impulse P [N s] (2D: N s/m):
/// f = P / dt [N] (2D: N/m), the impulses being integrals of the force over the step (method.md
/// §4); zero when dt <= 0 (no step solved yet). The one place a force is made of an impulse.
template <int Dim>
Vec<Dim> impulse_force(const Vec<Dim>& impulse, double dt) {
  if (!(dt > 0)) return Vec<Dim>::Zero();
  return impulse / dt;
}

/// Net impulse on each slot, in contact order: sum of the impulses of the contacts where it is B,
/// minus those where it is A [N s] (2D: N s/m).
template <int Dim>
std::vector<Vec<Dim>> net_impulses(const Problem<Dim>& problem);

/// Error measure shared by the solver and the tests: with the slot velocities implied by the
/// current impulses, sqrt(sum_c |P_c - local_c(P)|^2) / sqrt(sum_c |P_c|^2), where local_c is the
/// exact local solution of contact c by the problem's law with all other impulses fixed (0 when
/// every impulse is 0 and stays 0).
template <int Dim>
double error(const Problem<Dim>& problem);

/// The sweep order of problem's contacts and groups (SweepOrder).
template <int Dim>
SweepOrder sweep_order(const Problem<Dim>& problem);

/// Nonlinear Gauss-Seidel: sweeps the contacts in order, each solved exactly by the problem's law
/// (its local solver) with the others' current impulses, until error(problem) <= tolerance or
/// max_sweeps; starts from the impulses in `problem`. The exact nodal blocks and the
/// over-relaxation apply to the frictionless contacts of a Signorini law only (ContactLaw).
template <int Dim>
GsResult solve_gauss_seidel(Problem<Dim>& problem, const GsSettings& settings);

/// Sums (num, den) of error(problem) = sqrt(num) / sqrt(den) over every part of a problem that is
/// split between processes (docs/parallel.md); the identity for a whole problem.
using ErrorReduce = std::function<void(double& num, double& den)>;

/// The two sums of error(problem): num = sum_c |P_c - local_c(P)|^2, den = sum_c |P_c|^2 [(N s)^2].
template <int Dim>
void error_terms(const Problem<Dim>& problem, double& num, double& den,
                 StageTimers* timers = nullptr);

/// Gauss-Seidel on this process's part of a distributed problem (docs/parallel.md): the same sweeps
/// as solve_gauss_seidel over the local contacts, with the error summed over all parts by `reduce`
/// before every test, so that every process does the same number of sweeps. The parts must not
/// share slots (contacts coupled through a slot are solved by one process).
template <int Dim>
GsResult solve_gauss_seidel(Problem<Dim>& problem, const GsSettings& settings,
                            const ErrorReduce& reduce);

/// Writes the problem as text (one line per slot and contact, 17 significant digits).
template <int Dim>
void write_problem(const Problem<Dim>& problem, const std::string& path);

/// Reads a problem written by write_problem; throws InputError on malformed files.
template <int Dim>
Problem<Dim> read_problem(const std::string& path);

}  // namespace mpmcd::contact
