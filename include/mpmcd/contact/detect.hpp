#pragma once
/// Contact detection at x^n (method.md §4, docs/contact.md) on views of the grains' node fields and
/// their points: the grain-grain contacts at shared nodes (mass-gradient normals, gaps of the
/// points' domains) or at the grains' boundary faces, and the grain-wall contacts at grain nodes
/// or at the points' faces, with their warm-start impulses, appended to a Problem in an order that
/// does not depend on the thread count. The slots that carry them belong to the caller
/// (SlotMaker): mpm::ImplicitSolver makes them on its grain fields.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "mpmcd/contact/geometry.hpp"
#include "mpmcd/contact/problem.hpp"
#include "mpmcd/contact/settings.hpp"
#include "mpmcd/core/timer.hpp"
#include "mpmcd/core/types.hpp"
#include "mpmcd/grid/grid.hpp"

namespace mpmcd::contact {

/// A contact impulse of the last converged step, used to warm start the next one.
template <int Dim>
struct WarmImpulse {
  /// global grid node, -1 - grid cell of a face wall contact, or -1 - face number
  /// (point * 2 Dim + 2 axis + side) of a grain face contact [-]
  std::int64_t node = 0;
  std::int32_t a = 0;                   ///< body a: grain >= 0 or wall -1 - index [-]
  std::int32_t b = 0;                   ///< grain b [-]
  Vec<Dim> impulse = Vec<Dim>::Zero();  ///< impulse on b over the step [N s] (2D: N s/m)
};

/// The impulse of contact (key, a, b) in `previous` (sorted by (node, a, b)); zero if none [N s].
template <int Dim>
Vec<Dim> warm_impulse(std::span<const WarmImpulse<Dim>> previous, std::int64_t key, std::int32_t a,
                      std::int32_t b);

/// A grain's node field at x^n as detection reads it (mpm::GrainField's contact views).
template <int Dim>
struct FieldView {
  std::int64_t begin = 0;                        ///< the grain's first point [-]
  std::int64_t end = 0;                          ///< one past its last point [-]
  std::int32_t material = 0;                     ///< its material (friction matrix row) [-]
  double contact_mass = 0;                       ///< a node takes part from this mass on [kg]
  std::span<const double> m;                     ///< per active node: lumped mass [kg]
  std::span<const std::int64_t> node_global;     ///< per active node: global grid node [-]
  std::span<const Vec<Dim>> grad_m;              ///< per active node: outward mass gradient [kg/m]
  std::span<const Vec<Dim>> v;                   ///< per active node: velocity iterate [m/s]
  std::span<const std::int32_t> node_pts_start;  ///< per active node: start in node_pts (CSR) [-]
  std::span<const std::int32_t> node_pts;        ///< each active node's points, from begin [-]
  NodeBoxView<Dim> box;                          ///< its node box and active nodes
  /// The points of active node a, as offsets from `begin` [-].
  std::span<const std::int32_t> points_of(std::int32_t a) const {
    return node_pts.subspan(static_cast<std::size_t>(node_pts_start[a]),
                            static_cast<std::size_t>(node_pts_start[a + 1] - node_pts_start[a]));
  }
};

/// Which rank solves the contacts at a node (docs/parallel.md): the owner of the lowest grain
/// with a field there, or rank 0 for every node (`master`); this rank on one rank.
struct NodeRanks {
  bool distributed = false;    ///< the step runs on more than one rank
  bool master = false;         ///< rank 0 solves every contact (parallel::Scheme::kMaster)
  int me = 0;                  ///< this rank [-]
  std::span<const int> owner;  ///< owner rank of each grain [-]
};

/// The caller's slots (Problem::slots): the bodies of the contacts detection finds, made in the
/// order it finds them.
template <int Dim>
class SlotMaker {
 public:
  virtual ~SlotMaker() = default;
  /// The slot of grain g's active node a: one per (grain, node), made at its first use [-].
  virtual std::int32_t node_slot(std::int32_t g, std::int32_t a) = 0;
  /// A new slot of grain g carrying the weighted mean of the velocities of its active `nodes`
  /// (weights summing to 1) [-].
  virtual std::int32_t weighted_slot(std::int32_t g, const std::vector<std::int32_t>& nodes,
                                     const std::vector<double>& weights) = 0;
  /// Sets slot s's warm-start key (WarmImpulse::node of its contacts) [-].
  virtual void set_key(std::int32_t s, std::int64_t key) = 0;
};

/// What one detection reads: settings, grid, the points' domains, the grains' fields.
template <int Dim>
struct DetectInput {
  const ContactSettings<Dim>* settings = nullptr;  ///< contact settings and walls
  const grid::Grid<Dim>* grid = nullptr;           ///< the background grid
  DomainsView<Dim> points;                         ///< every point's domain at x^n
  std::span<const FieldView<Dim>> fields;          ///< per grain (only `local` ones are read)
  std::span<const std::size_t> local;  ///< the grains computed here (owned and ghost), ascending
  std::span<const WarmImpulse<Dim>> previous;  ///< last step's impulses, sorted by (node, a, b)
  NodeRanks ranks;                             ///< who solves the contacts at a node
  double time = 0;                             ///< t^n (wall positions) [s]
  double dt = 0;                               ///< the step [s]
  Vec<Dim> gravity = Vec<Dim>::Zero();         ///< body acceleration [m/s^2]
  StageTimers* timers = nullptr;  ///< stage timers (contact.detect.faces, .walls; threads)
};

/// Contact detection with its work space kept from step to step (per node and per point arrays).
template <int Dim>
class Detector {
 public:
  /// Appends the step's contacts to problem.contacts, their slots made by `slots`; a frictionless
  /// contact's warm start is not yet projected on its normal. Returns the items examined (node
  /// fields, pairs, point pairs and faces: Comm::count_work) [-].
  double detect(const DetectInput<Dim>& in, Problem<Dim>& problem, SlotMaker<Dim>& slots);

 private:
  // Grain-grain contacts at the points' boundary faces (ContactSettings::grain_faces) for the
  // pairs sharing nodes, links = (grain A < grain B, A's active node, B's active node); appends
  // them and returns the items examined [-].
  double grain_face_contacts(const DetectInput<Dim>& in,
                             std::vector<std::array<std::int32_t, 4>>& links, Problem<Dim>& problem,
                             SlotMaker<Dim>& slots);
  std::vector<std::uint32_t> node_stamp_;  // per global node: step stamp
  std::vector<std::int32_t> node_head_;    // per global node: first field entry
  std::uint32_t stamp_ = 0;
  // Per point: sum_i |F r_i|, a bound of its domain's extent along any direction [m].
  std::vector<double> point_reach_;
  // Per point, with face contacts between grains: (F D0)^-1, the inverse of its domain's map [1/m].
  std::vector<Mat<Dim>> point_dinv_;
  // Per point and face (2 k + side), with face contacts between grains: the point of the same
  // grain whose domain held the probe beyond that face at the last detection, or -1 (a hint
  // that only shortens the interior test; grain_face_contacts) [-].
  std::vector<std::array<std::int64_t, 2 * Dim>> interior_hint_;
};

/// A slot for the faces of points `pts` facing a wall of unit normal n (into the domain): the mean
/// velocity of the faces' corners (face_toward) interpolated from grain g's active nodes, made by
/// `slots`; writes the mean face centre to x_face [m]. -1 if the faces touch no active node [-].
template <int Dim>
std::int32_t face_slot(const FieldView<Dim>& field, std::int32_t g, const DomainsView<Dim>& points,
                       const std::vector<std::int64_t>& pts, const Vec<Dim>& n, Vec<Dim>& x_face,
                       SlotMaker<Dim>& slots);

extern template class Detector<2>;
extern template class Detector<3>;

}  // namespace mpmcd::contact
