#pragma once
/// The work model of the step (docs/parallel.md, "Timers and the serial share", "Re-balancing"):
/// costs of the solver's stages in evaluations of a material point, used to count each rank's
/// work between synchronisations (Comm::count_work) and to balance the grains' work over the
/// ranks. Fitted on the 300-grain slice (bench_parallel) on one rank, one point evaluation
/// costing 82 ns that day; the exchange weights on traces of the slice on 2 ranks.

namespace mpmcd::parallel::cost {

/// P2G with the previous step's G2P, per point (7.5 ms for 61k points) [point evaluations].
inline constexpr double kP2g = 1.5;
/// Contact detection, per point (8.3 ms for 61k points) [point evaluations].
inline constexpr double kDetect = 1.7;
/// A grain's set-up of a step, per point: P2G and detection, counted with the first Newton
/// iteration when re-balancing [point evaluations].
inline constexpr double kSetup = kP2g + kDetect;
/// One pass of Gauss-Seidel or of its error over a contact: 0.57 by the slice's benchmark (2.9 ms
/// for 61.8k), 1.35 times more between two error tests in the traces of the distributed solve
/// (partition and master, 2 ranks, 2026-11-21) [point evaluations].
inline constexpr double kContactPass = 0.77;
/// One item of contact detection: a node field, a pair of fields, a pair of points in a gap (8.3
/// ms for 145k items on one rank) [point evaluations].
inline constexpr double kDetectItem = 0.7;
/// The exchanges' bookkeeping (bench_parallel --trace, master scheme, where rank 1 examines and
/// packs every contact node for rank 0; 100 ns per unit that day): one value packed or
/// unpacked, a slot served, asked or updated, or a contact in the pass after the solve (5-20 ns)
/// [point evaluations].
inline constexpr double kExchangeItem = 0.1;
/// One node-in-box or node-to-wall test while choosing the nodes to send (50 ns) [point
/// evaluations].
inline constexpr double kBoxTest = 0.5;
/// One overlap test of two grains' boxes (7 ns) [point evaluations].
inline constexpr double kPairTest = 0.07;
/// One CG iteration per matrix non-zero with the tangent assembly (6.5 ms for 1.67e6) [point
/// evaluations].
inline constexpr double kCgWork = 0.048;

}  // namespace mpmcd::parallel::cost
