#pragma once
/// The process communicator (docs/parallel.md): rank, size, deterministic reductions, neighbour
/// exchange and byte counters. The only place that talks to MPI (<mpi.h> is included by
/// src/parallel/comm.cpp alone); without MPI (MPMCD_WITH_MPI off) or outside mpirun it is one
/// process and every call is a local no-op.
#include <cstdint>
#include <cstring>
#include <map>
#include <source_location>
#include <string>
#include <vector>

namespace mpmcd::parallel {

/// A byte buffer with typed append/read (plain data only).
class Buffer {
 public:
  /// Appends the bytes of a trivially copyable value.
  template <class T>
  void put(const T& value) {
    const auto* p = reinterpret_cast<const char*>(&value);
    bytes_.insert(bytes_.end(), p, p + sizeof(T));
  }
  /// Reads the next value (in put order).
  template <class T>
  T get() {
    T value;
    std::memcpy(static_cast<void*>(&value), bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }
  /// True when every byte has been read.
  bool done() const { return pos_ >= bytes_.size(); }
  /// The raw bytes.
  std::vector<char>& bytes() { return bytes_; }
  /// The raw bytes (read only).
  const std::vector<char>& bytes() const { return bytes_; }

 private:
  std::vector<char> bytes_;
  std::size_t pos_ = 0;
};

/// The world communicator of the run; one per process (Comm::world()).
class Comm {
 public:
  /// The world communicator; initialises MPI on first use (a singleton without mpirun).
  static Comm& world();
  /// A communicator of this process alone (one rank, never touches MPI): the serial runs' comm,
  /// on which every collective and exchange below is a no-op.
  static const Comm& alone();
  /// Finalises MPI (call once at the end of main; later calls do nothing).
  static void finalize();
  /// This process's rank [-].
  int rank() const { return rank_; }
  /// Number of processes [-].
  int size() const { return size_; }
  /// True when built with MPI support.
  static bool has_mpi();
  /// Waits for every rank.
  void barrier(std::source_location at = std::source_location::current()) const;
  /// Ends every process of the job with exit status `code` (an error seen by this rank alone,
  /// which would leave the others waiting); returns only on one rank or without MPI.
  void abort(int code) const;
  /// Element-wise sum over ranks, added in rank order (bitwise reproducible for a rank count).
  void sum(std::vector<double>& values,
           std::source_location at = std::source_location::current()) const;
  /// Element-wise integer sum over ranks.
  void sum(std::vector<std::int64_t>& values,
           std::source_location at = std::source_location::current()) const;
  /// Element-wise maximum over ranks.
  void max(std::vector<double>& values,
           std::source_location at = std::source_location::current()) const;
  /// Element-wise minimum over ranks (integers).
  void min(std::vector<std::int64_t>& values,
           std::source_location at = std::source_location::current()) const;
  /// Every rank's bytes, indexed by rank (all-gather of variable size).
  std::vector<std::vector<char>> allgather(
      const std::vector<char>& mine,
      std::source_location at = std::source_location::current()) const;
  /// Every rank's bytes at `root`, indexed by rank (its own included), point-to-point (no
  /// collective over the other ranks); empty on the other ranks.
  std::vector<std::vector<char>> gather(
      const std::vector<char>& mine, int root,
      std::source_location at = std::source_location::current()) const;
  /// Root's bytes on every rank.
  void broadcast(std::vector<char>& bytes, int root,
                 std::source_location at = std::source_location::current()) const;
  /// Point-to-point exchange: sends out[r] to each rank r in `out` and receives from each rank in
  /// `from` (both sides must agree); returns the received buffers by rank.
  std::map<int, Buffer> exchange(const std::map<int, Buffer>& out, const std::vector<int>& from,
                                 std::source_location at = std::source_location::current()) const;
  /// Bytes this rank has sent so far (point-to-point and its share of collectives) [B].
  std::int64_t bytes_sent() const { return bytes_sent_; }
  /// Messages this rank has sent so far [-].
  std::int64_t messages_sent() const { return messages_sent_; }

  /// Starts recording, from now, this rank's work interval before each synchronisation (every
  /// call above), for solo_report; clears what was recorded before. Every rank must call it at
  /// the same point of the run.
  void record_syncs() const;
  /// Adds work done by this rank since its last synchronisation, in deterministic units (point
  /// evaluations; ImplicitSolver counts them), for the counted serial fraction of solo_report.
  void count_work(double units) const {
    if (recording_) pending_units_ += units;
  }
  /// Time in which one rank works alone, measured synchronisation by synchronisation
  /// (collective; docs/parallel.md "Serial fraction"): for each synchronisation k, with d_rk the
  /// time rank r worked since it left synchronisation k-1, the last rank to arrive worked alone
  /// for max_r d_rk - (second largest d_rk). Exact for two ranks; for more, neighbour exchanges
  /// are not global, and the figure is that of the two slowest ranks.
  struct SoloReport {
    double solo_s = 0;  ///< sum over synchronisations of the time one rank works alone [s]
    /// The same with each work interval in process CPU time (without the time the rank was
    /// descheduled: the scheme's load imbalance; meaningful with one thread per rank) [s].
    double solo_cpu_s = 0;
    /// Counted serial fraction: sum over synchronisations of max - second largest of the
    /// ranks' work units (count_work), over the sum of every rank's units [-]. Free of the
    /// machine's timing noise; as good as the cost model behind the units.
    double solo_work_fraction = 0;
    double solo_units = 0;                  ///< numerator of solo_work_fraction [units]
    double total_units = 0;                 ///< denominator of solo_work_fraction [units]
    double wait_s = 0;                      ///< time in synchronisations, mean over ranks [s]
    std::int64_t syncs = 0;                 ///< synchronisations recorded [-]
    bool consistent = true;                 ///< every rank made the same sequence of calls
    std::map<std::string, double> by_site;  ///< solo_s by the code line that synchronised [s]
  };
  /// The report since record_syncs (collective; complete on rank 0, totals on every rank).
  SoloReport solo_report() const;
  /// Also writes every recorded synchronisation to the CSV file `path` (rank 0; every rank must
  /// call it, before record_syncs): one row per synchronisation with its code line and each
  /// rank's wall-time work interval [s], CPU-time interval [s] and counted units [-]. Runs that
  /// are bitwise identical make the same rows except for the times, so tools/serial_ensemble.py
  /// averages each synchronisation's intervals over repeated runs (docs/parallel.md).
  void trace_syncs(const std::string& path) const;

 private:
  Comm();
  struct AloneTag {};
  explicit Comm(AloneTag) {}
  friend class SyncMark;
  // Records the arrival at a synchronisation (work interval since the last one) [s].
  void arrive(const std::source_location& at) const;
  // Marks the end of a synchronisation (start of the next work interval).
  void depart() const;
  // Folds the recorded intervals into the totals (collective; every rank at the same call).
  void fold_syncs() const;
  // Appends the gathered intervals (rank-major, n per rank) to the trace_syncs file (rank 0).
  void write_trace(const std::vector<double>& all_w, const std::vector<double>& all_c,
                   const std::vector<double>& all_u, std::int64_t n) const;
  int rank_ = 0, size_ = 1;
  mutable std::int64_t bytes_sent_ = 0, messages_sent_ = 0;
  mutable bool recording_ = false;
  mutable double last_exit_ = 0;            // steady clock at the end of the last sync [s]
  mutable double last_arrival_ = 0;         // steady clock at the start of this sync [s]
  mutable double waited_ = 0;               // time inside syncs since record_syncs [s]
  mutable std::vector<double> work_;        // work interval before each sync [s]
  mutable std::vector<double> work_cpu_;    // the same in process CPU time [s]
  mutable std::vector<double> units_;       // counted work units before each sync [-]
  mutable double pending_units_ = 0;        // units counted since the last sync [-]
  mutable double last_exit_cpu_ = 0;        // process CPU time at the end of the last sync [s]
  mutable std::vector<std::int32_t> line_;  // source line of each sync
  mutable std::vector<const char*> file_;   // source file of each sync
  mutable std::int64_t collectives_ = 0;    // global collectives since record_syncs
  mutable SoloReport folded_;               // totals of the intervals already folded
  mutable std::string trace_path_;          // trace_syncs file ("" = none)
  mutable std::int64_t traced_ = 0;         // synchronisations written to it
};

}  // namespace mpmcd::parallel
