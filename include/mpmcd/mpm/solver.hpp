#pragma once
/// The implicit theta-method MPM step (method.md §2): P2G per grain, Newton-Raphson on end-of-step
/// nodal velocities with the consistent tangent, per-grain sparse linear solves, G2P on commit.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <source_location>
#include <span>
#include <string>
#include <vector>

#include "mpmcd/contact/active_set.hpp"
#include "mpmcd/contact/detect.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/core/timer.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/grid/grid.hpp"
#include "mpmcd/grid/shape.hpp"
#include "mpmcd/materials/law.hpp"
#include "mpmcd/mpm/grain_field.hpp"
#include "mpmcd/mpm/settings.hpp"
#include "mpmcd/parallel/comm.hpp"
#include "mpmcd/parallel/cost_model.hpp"
#include "mpmcd/parallel/partition.hpp"
#include "mpmcd/points/point_set.hpp"

namespace mpmcd::mpm {

/// Outcome of one attempted step.
struct StepStats {
  bool converged = false;           ///< all grains converged
  int iterations = 0;               ///< Newton iterations (max over grains)
  std::int64_t linear_solves = 0;   ///< linear solves, summed over grains
  std::int64_t factorizations = 0;  ///< Newton-matrix factorisations, summed over grains
  /// Of those, the dense LL^T ones (Settings::dense_fill), summed over grains [-].
  std::int64_t dense_factorizations = 0;
  /// Factorisations redone with the projected tangent because M + theta^2 dt^2 K was indefinite
  /// (docs/accuracy.md, "Indefinite Newton matrices"), summed over grains [-].
  std::int64_t projected_factorizations = 0;
  /// Points whose CPDI domain spans more than two cells along an axis and whose shape functions
  /// used it shrunk to fit the window (grid::fit_cpdi_window), summed over grains [-].
  std::int64_t shrunk_domains = 0;
  /// Points whose CPDI domain F^{n+1} D0 at the end of the step does not fit the window
  /// (grid::fits_cpdi_window), summed over grains and ranks: the points to split (CPDI only) [-].
  std::int64_t oversized_domains = 0;
  /// Work of the contact impulses on the grains over the step, sum_I P_I . (v_I^n + v_I^{n+1}) / 2
  /// over every grain node (the exact kinetic-energy change they cause on the grid) [J] (2D: J/m).
  double contact_work = 0;
  /// Kinetic energy the transfers remove over the step (docs/accuracy.md, energy ledger): the
  /// P2G's, sum_p m_p |v_p^n|^2/2 - sum_I m_I |v_I^n|^2/2, plus the G2P's,
  /// sum_I m_I |v_I^{n+1}|^2/2 - sum_p m_p |v_p^{n+1}|^2/2, over every grain [J] (2D: J/m).
  double transfer_loss = 0;
  /// Work of the internal forces on the grid, dt sum_I [(1 - theta) f_int^n + theta f_int^{n+1}]
  /// . (v_I^n + v_I^{n+1})/2 (minus the stress power; -(stored energy change) when exact) [J].
  double stress_work = 0;
  /// Work of the body forces on the grid, dt sum_I f_ext,I . (v_I^n + v_I^{n+1})/2 [J] (2D: J/m).
  double body_work = 0;
  std::vector<double> residual_history;  ///< per iteration: max over grains of |R| / reference
  std::string failure;                   ///< why the step failed ("" if converged)
  bool retryable = true;             ///< false if a smaller dt cannot help (a point left the grid)
  std::int64_t grain = -1;           ///< grain involved in the failure, -1 if none
  std::int64_t point = -1;           ///< point involved in the failure, -1 if none
  std::int64_t contacts = 0;         ///< contact candidates (grain-grain and grain-wall)
  std::int64_t active_contacts = 0;  ///< contacts with a positive normal impulse
  std::int64_t gs_sweeps = 0;        ///< Gauss-Seidel sweeps, summed over Newton iterations
  double gs_error = 0;               ///< final Gauss-Seidel error measure [-]
  std::vector<std::array<double, 3>>
      wall_force;  ///< force of the grains on each wall [N] (2D: N/m)
};

/// A contact impulse of the last converged step (the contact module's, contact/detect.hpp).
using contact::WarmImpulse;

/// Implicit MPM stepper: grains with their own nodal fields (GrainField, whose stages it calls
/// grain by grain), coupled by Contact Dynamics. Holds non-owning references to the points,
/// grains and laws, which must outlive it.
template <int Dim>
class ImplicitSolver {
 public:
  /// `laws[m]` is the law of material m; points of a grain are contiguous (points::Grain).
  ImplicitSolver(const grid::Grid<Dim>& grid, const Settings<Dim>& settings,
                 points::PointSet<Dim>& points, const std::vector<points::Grain>& grains,
                 std::vector<const materials::Law<Dim>*> laws);
  ~ImplicitSolver();
  ImplicitSolver(const ImplicitSolver&) = delete;
  ImplicitSolver& operator=(const ImplicitSolver&) = delete;

  /// Replaces the nodal velocity boundary conditions (later sets override earlier ones).
  void set_boundary_conditions(const std::vector<VelocityBC<Dim>>& bcs);
  /// Runs the steps on several processes (docs/parallel.md): this rank computes the grains g with
  /// owner[g] == comm.rank() (their points must be current here; others' may be stale); contacts
  /// at a node are solved by the rank owning the node's lowest grain (kPartition) or by rank 0
  /// (kMaster). Needs the lumped Delassus operator when comm has more than one rank.
  /// Collective on several ranks: every rank then holds every rank's warm-start impulses, so
  /// that a node whose contacts change rank keeps its impulses (re-balancing).
  void set_distribution(const parallel::Comm* comm, std::vector<int> owner,
                        parallel::Scheme scheme);
  /// Rank computing each grain (all 0 when serial).
  const std::vector<int>& owner() const { return owner_; }
  /// Work of each grain computed here since the last call, grain-major with
  /// parallel::kWorkPhases phases per grain (docs/parallel.md "Re-balancing"), in point
  /// evaluations summed over steps (0 for grains of other ranks); deterministic. Resets the counts.
  std::vector<double> take_grain_work();
  /// The work counts since the last take_grain_work, grain x phase [-] (checkpoints).
  const std::vector<double>& grain_work() const { return grain_work_; }
  /// Replaces the work counts (a restart; 0 for grains of other ranks) [-].
  void set_grain_work(std::vector<double> work) { grain_work_ = std::move(work); }
  /// True when the step runs on more than one rank.
  bool distributed() const { return comm_->size() > 1; }
  /// Sets the time t^n [s] of the next step (wall positions).
  void set_time(double t) { time_ = t; }
  /// Replaces the rigid walls (their positions and velocities for the next step; same count and
  /// order as the settings' walls: a wall's index names it in contacts and forces).
  void set_walls(std::vector<walls::Wall<Dim>> walls);
  /// The contact problem of the last step (impulses solved), for output and replay.
  const contact::Problem<Dim>& contact_problem() const { return problem_; }
  /// Warm-start impulses kept from the last converged step, sorted by (node, a, b).
  const std::vector<WarmImpulse<Dim>>& warm_start() const { return previous_; }
  /// Replaces the warm-start impulses (a restart); sorts them by (node, a, b).
  void set_warm_start(std::vector<WarmImpulse<Dim>> impulses);
  /// Follows a renumbering of the points (points::apply_splits): `index[p]` is old point p's new
  /// index; renames the points in the warm-start keys of grain-face contacts.
  void renumber_points(std::span<const std::int64_t> index);
  /// Every rank's warm-start impulses, sorted by (node, a, b), one per contact (collective on
  /// several ranks; this rank's own when serial): checkpoints and re-distribution.
  std::vector<WarmImpulse<Dim>> gather_warm_start() const;
  /// Attempts the step t -> t + dt [s] from the committed point state; changes no point data.
  StepStats solve_step(double dt);
  /// Commits the last converged step: G2P positions and velocities, F, stress, volume, history.
  void commit();
  /// Stage timers (P2G, newton.assemble, newton.solve, G2P) accumulated over the run [s].
  StageTimers& timers() { return timers_; }
  /// The settings in use.
  const Settings<Dim>& settings() const { return settings_; }
  /// The grid.
  const grid::Grid<Dim>& grid() const { return grid_; }
  /// Nodal mass of grain g's field after the last solve_step, summed [kg] (diagnostic).
  double field_mass(std::size_t g) const;
  /// Nodal momentum sum_I m_I v_I^{n+1} of grain g after the last solve_step [kg m/s].
  Vec<Dim> field_momentum(std::size_t g) const;

 private:
  struct GrainWork;
  class Slots;  // contact::SlotMaker on this solver's grain fields (contact_detect.cpp)
  // Grain g's Newton matrix, assembled (if stale) and factorised: prepare_factor with the solver's
  // points, law and the grain's contact compliance. False on a failed factorisation.
  bool grain_factor(std::size_t g, double dt);
  // Grain g's compliance group G (and Z) from its current factorisation; true when G was
  // recomputed (a new factorisation, or a lumped group).
  bool grain_compliance(std::size_t g);
  // Fills slot_basis_ and slot_rank_ from this step's contacts.
  void build_slot_bases();
  // contact.detect: the step's slots and contacts (contact::Detector on views of the grain
  // fields), their warm start and the compliance groups.
  void detect_contacts(double dt);
  // contact.solve: the contact problem with the grains' current iterates, the new impulses
  // applied to the grains; returns the relative impulse change [-]. On several ranks, the
  // distributed Gauss-Seidel (update_contacts_distributed).
  double update_contacts(StepStats& stats);
  std::int32_t slot_of(std::int32_t g, std::int32_t a);
  // A slot of grain g carrying the weighted mean of the velocities of its active `nodes`.
  std::int32_t weighted_slot(std::int32_t g, const std::vector<std::int32_t>& nodes,
                             const std::vector<double>& weights);
  // Velocity of slot s from its grain's current nodal iterate: sum_k w_k v_{a_k} [m/s].
  Vec<Dim> slot_velocity(std::size_t s) const;
  // The lumped response of grain g's node a to its new contact impulse P [N s], on one rank or
  // several: v_a = v_free + P / m_a with v_free = v_a - P_a / m_a (method.md §4), P_a = P; adds
  // m_a |dv|^2 to dv2[g] (which starts at -1: no change) [kg m^2/s^2]. Nothing when P = P_a.
  void apply_lumped_impulse(std::int32_t g, std::int32_t a, const Vec<Dim>& P,
                            std::vector<double>& dv2);
  // Nodal impulses of every grain from the slots' impulses slot_P_: P_a = sum_s w_sa P_s.
  void spread_slot_impulses();
  // With ContactSettings::face_normals_at_end: the step's grain-grain face contacts, each with
  // its face (point, axis, side) and the K_blk positions of the (I, J) blocks of its normal's
  // stiffness in the face grain's Newton matrix (face_normals.cpp); made after detection.
  void prepare_face_normals();
  // contact.follow: each grain-grain face contact's normal from the iterate's F^{n+1} (its
  // impulse turned with it), the grains' nodal impulses and residuals again, and the symmetric
  // part of the normal's stiffness into each face grain's follower_K (docs/contact.md, "Face
  // normals at the end of the step").
  void follow_face_normals();
  // follow_face_normals' parts: the slots' and grains' impulses and residuals after the normals
  // turned; the normals' stiffness into follower_K.
  void follow_impulses();
  void follow_stiffness();
  // Runs fn(g, work) on the threads for each grain this rank owns that has not failed.
  template <class Fn>
  void on_live_grains(Fn&& fn);
  // Agrees on the lowest failing grain over the ranks (reduced here when `lowest` < 0, else that
  // grain) and gives every rank its owner's failure message; false when no rank failed.
  bool sync_failure(StepStats& stats, std::int64_t lowest = -1);
  // Sorts warm-start impulses by (node, a, b) and keeps one per contact.
  static void sort_unique(std::vector<WarmImpulse<Dim>>& impulses);
  // The ghost grains' node boxes and contact nodes from their owners (local_ gains the ghosts);
  // nothing on one rank.
  void exchange_entries();
  // The ghost slots of this rank's contacts: the links to their owners, and have_contacts_ (any
  // rank has contacts).
  void exchange_requests();
  double update_contacts_distributed(StepStats& stats);
  // Reduces `values` element-wise over the ranks with `op` (parallel::Comm::sum, max or min; `at`
  // names the call site in the synchronisation report), timed as newton.check.comm; nothing to do
  // on one rank.
  template <class T>
  void over_ranks(std::vector<T>& values,
                  void (parallel::Comm::*op)(std::vector<T>&, std::source_location) const,
                  std::source_location at = std::source_location::current()) {
    if (!distributed()) return;
    ScopedStage tc(&timers_, "newton.check.comm");
    (comm_->*op)(values, at);
  }
  grid::Grid<Dim> grid_;
  Settings<Dim> settings_;
  points::PointSet<Dim>& points_;
  const std::vector<points::Grain>& grains_;
  std::vector<const materials::Law<Dim>*> laws_;
  std::vector<std::unique_ptr<GrainWork>> work_;
  PrescribedNodes<Dim> prescribed_;  // prescribed velocity components per global node
  TrialState<Dim> trial_;            // trial state per point (committed only by commit())
  // Contact state: the problem of the step, slot -> (grain, active node), warm-start impulses.
  contact::Problem<Dim> problem_;
  std::vector<std::pair<std::int32_t, std::int32_t>> slot_ref_;
  // Per slot: its grain's active nodes and weights (CSR; a node slot has one node of weight 1),
  // and the impulse it currently applies to its grain [N s].
  std::vector<std::int32_t> slot_start_{0}, slot_node_;
  std::vector<double> slot_weight_;
  std::vector<Vec<Dim>> slot_P_;
  // Per slot: an orthonormal basis (first slot_rank_ columns) of the directions its contacts'
  // impulses take this step: the normals of its frictionless contacts, all of R^Dim when one is
  // frictional (build_slot_bases; the compliance is computed on these directions only).
  std::vector<Mat<Dim>> slot_basis_;
  std::vector<int> slot_rank_;
  bool slot_bases_valid_ = false;  // built for this step's contacts
  std::vector<char> slot_is_face_;
  // prepare_face_normals: per grain-grain face contact (grouped by the face's grain, CSR
  // face_start_ over grains) its contact, point, axis and side, and its stiffness blocks: slot
  // entry q of its face slot (node I, weight w), window entry a of the point (node J), and the
  // K_blk indices of (I, J) and (J, I).
  struct FaceNormal {
    std::int32_t contact;
    std::int64_t point;
    int axis;
    double sign;
    std::int32_t first_block, end_block;
  };
  struct FaceBlock {
    std::int32_t q, a;
    std::int64_t ij, ji;
  };
  std::vector<FaceNormal> face_normals_;
  std::vector<Vec<Dim>> follow_normal_;  // per face_normals_ entry: its normal at the iterate
  std::vector<FaceBlock> face_blocks_;
  std::vector<std::int32_t> face_start_;
  // The slots by grain, ascending within each (CSR over grains), for spread_slot_impulses on the
  // threads; made for `grain_slots_for_` slots of this step (-1: not yet).
  std::vector<std::int32_t> grain_slot_start_, grain_slots_;
  std::int64_t grain_slots_for_ = -1;
  // Per slot: warm-start key, the global node of a node slot, -1 - cell of a face slot.
  std::vector<std::int64_t> slot_key_;
  std::vector<std::uint32_t> slot_stamp_;  // per global node: step stamp
  std::vector<std::int32_t> slot_head_;    // per global node: first slot
  std::vector<std::int32_t> slot_next_;    // per slot: next slot at the same node
  std::uint32_t stamp_ = 0;
  bool gs_converged_ = true;
  std::vector<WarmImpulse<Dim>> previous_;  // sorted by (node, a, b)
  // Distribution (docs/parallel.md): owner rank per grain, this rank's grains, ghost grains (their
  // contact nodes received from their owners), the neighbour ranks and, per neighbour, the slots
  // whose velocity / impulse travel each Newton iteration.
  // The ranks of the step: parallel::Comm::alone() until set_distribution (every collective and
  // exchange of the step is then a no-op, so that solve_step runs one code on any rank count).
  const parallel::Comm* comm_ = &parallel::Comm::alone();
  parallel::Scheme scheme_ = parallel::Scheme::kPartition;
  std::vector<int> owner_;
  std::vector<std::size_t> owned_, local_;  // owned grains; owned + ghost grains (ascending)
  std::vector<std::uint8_t> role_;          // per grain: 0 absent, 1 owned, 2 ghost
  std::vector<int> neighbours_;
  std::vector<std::array<std::int64_t, 2 * Dim>> boxes_;  // node box lo, hi (inclusive) per grain
  struct Link {
    std::vector<std::pair<std::int32_t, std::int32_t>> serve;  // my (grain, active) asked for
    std::vector<std::int32_t> ask;  // my problem's ghost slots owned there, in request order
  };
  std::map<int, Link> links_;
  bool have_contacts_ = false;  // some rank has contacts this step
  // Work counts per grain and phase since take_grain_work, in point evaluations [-].
  std::vector<double> grain_work_;
  // The work count of grain g in the phase of Newton iteration `iteration`.
  double& phase_work(std::size_t g, int iteration);
  // The Gauss-Seidel settings with this solver's timers (threaded sweeps, ThreadedRegion) and its
  // tuner (threads or one thread per sweep, by measured cost; kept from step to step).
  contact::GsSettings gs_settings() {
    contact::GsSettings gs = settings_.contact.gs;
    gs.timers = &timers_;
    gs.tuner = &gs_tuner_;
    return gs;
  }
  ThreadTuner gs_tuner_;
  // The sweep order of this step's contacts and groups, made at the step's first Gauss-Seidel
  // solve and kept for the later Newton iterations (the same contacts and groups).
  contact::SweepOrder sweep_order_;
  bool sweep_order_ready_ = false;
  // The active-set solver's W and factorisation, kept while this step's contacts and the grains'
  // compliances stay the same (cleared at detection and when a G is recomputed).
  contact::ActiveSetCache as_cache_;
  // Slots this rank serves to others and asks from others (links_) [-].
  std::pair<std::size_t, std::size_t> link_sizes() const;
  // Items of the last contact detection on this rank [-].
  double detect_items_ = 0;
  // Contact detection (its work space kept from step to step) and its views of the grain fields.
  contact::Detector<Dim> detector_;
  std::vector<contact::FieldView<Dim>> field_views_;
  double time_ = 0.0;
  double dt_ = 0.0;
  bool step_ready_ = false;
  StageTimers timers_;
};

extern template class ImplicitSolver<2>;
extern template class ImplicitSolver<3>;

}  // namespace mpmcd::mpm
