#pragma once
/// Whole-model operations of a distributed run (docs/parallel.md): dealing the grains of a model,
/// gathering the committed point state of every grain on one rank (outputs), and the per-stage
/// timer report with the serial share of each stage.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "mpmcd/contact/problem.hpp"
#include "mpmcd/parallel/comm.hpp"
#include "mpmcd/parallel/partition.hpp"
#include "mpmcd/points/point_set.hpp"

namespace mpmcd::parallel {

/// Rank of each grain: bisection of the centroids weighted by point count (kPartition) or greedy
/// dealing by volume (kMaster), over comm.size() ranks; the same on every rank.
template <int Dim>
std::vector<int> deal_grains(const points::PointSet<Dim>& points,
                             const std::vector<points::Grain>& grains, Scheme scheme, int ranks);

/// Copies the committed state (x, v, F, sigma, sigma_zz, volume, history) of every grain from its
/// owner to rank `root` (root < 0: to every rank). Output-time traffic, not per step.
template <int Dim>
void gather_points(const Comm& comm, points::PointSet<Dim>& points,
                   const std::vector<points::Grain>& grains, const std::vector<int>& owner,
                   int root);

/// Every rank's contacts merged on rank `root` in the canonical order (node of B, body A, grain
/// B; walls as -1 - index), with one slot per contact side carrying its grain and node: the same
/// problem whatever the rank count (outputs, Z). Other ranks get an empty problem.
template <int Dim>
contact::Problem<Dim> gather_contacts(const Comm& comm, const contact::Problem<Dim>& local,
                                      int root);

/// Re-balancing of the partition scheme: with `weights` the work of each owned grain since the
/// last call, kWorkPhases values per grain (0 for others; deterministic counts, see
/// ImplicitSolver::take_grain_work), the imbalance (partition.hpp) of the ranks' sums per phase;
/// above `threshold` the grains are bisected again at their current centroids with those weights,
/// and each grain whose rank changes is sent (committed state) from its old to its new owner.
/// Collective; returns the imbalance measured before [-].
template <int Dim>
double rebalance(const Comm& comm, points::PointSet<Dim>& points,
                 const std::vector<points::Grain>& grains, std::vector<int>& owner,
                 const std::vector<double>& weights, double threshold, bool& moved);

/// One stage of the timer report, over ranks [s].
struct StageTime {
  std::string name;         ///< stage name (".comm" suffix: communication inside that stage)
  double max = 0;           ///< largest time over ranks [s]
  double mean = 0;          ///< mean over ranks [s]
  double min = 0;           ///< smallest over ranks [s]
  double serial = 0;        ///< stage-total imbalance: max - second largest of work [s]
  bool nested = false;      ///< inside another stage (not added to the step total)
  bool one_thread = false;  ///< mostly on one thread per rank (the measured share: below)
};

/// Gathers every rank's stage totals [s] and derives the report (collective call).
std::vector<StageTime> stage_report(const Comm& comm, const std::map<std::string, double>& totals);

/// The report as CSV: stage,max_s,mean_s,min_s,work_serial_s,nested,one_thread, then summary
/// rows: wall, serial fraction of one rank (from `solo`, synchronisation by synchronisation),
/// stage-total imbalance, time in synchronisations, one-thread share, bytes sent per rank per
/// step, and the solo time of each synchronising code line.
std::string stage_report_csv(const std::vector<StageTime>& rows, double wall_seconds, int ranks,
                             int threads, long long steps, double bytes_per_rank_step,
                             const Comm::SoloReport& solo);

/// Measured share of the wall time in which a rank works on one thread only [-]: the wall time
/// minus its time in OpenMP regions that ran on several threads (stage kThreadedStage, mean over
/// ranks) and minus its time waiting in synchronisations (`solo.wait_s`), over the wall time;
/// 0 with one thread. Load imbalance between the threads inside a region is not in it.
double one_thread_fraction(const std::vector<StageTime>& rows, double wall_seconds, int threads,
                           const Comm::SoloReport& solo);

}  // namespace mpmcd::parallel
