#pragma once
/// The process communicator (docs/parallel.md): rank, size, deterministic reductions, neighbour
/// exchange and byte counters. The only place that talks to MPI (<mpi.h> is included by
/// src/parallel/comm.cpp alone); without MPI (MPMCD_WITH_MPI off) or outside mpirun it is one
/// process and every call is a local no-op.
#include <cstdint>
#include <cstring>
#include <map>
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
  /// Finalises MPI (call once at the end of main; later calls do nothing).
  static void finalize();
  /// This process's rank [-].
  int rank() const { return rank_; }
  /// Number of processes [-].
  int size() const { return size_; }
  /// True when built with MPI support.
  static bool has_mpi();
  /// Waits for every rank.
  void barrier() const;
  /// Ends every process of the job with exit status `code` (an error seen by this rank alone,
  /// which would leave the others waiting); returns only on one rank or without MPI.
  void abort(int code) const;
  /// Element-wise sum over ranks, added in rank order (bitwise reproducible for a rank count).
  void sum(std::vector<double>& values) const;
  /// Element-wise integer sum over ranks.
  void sum(std::vector<std::int64_t>& values) const;
  /// Element-wise maximum over ranks.
  void max(std::vector<double>& values) const;
  /// Element-wise minimum over ranks (integers).
  void min(std::vector<std::int64_t>& values) const;
  /// Every rank's bytes, indexed by rank (all-gather of variable size).
  std::vector<std::vector<char>> allgather(const std::vector<char>& mine) const;
  /// Root's bytes on every rank.
  void broadcast(std::vector<char>& bytes, int root) const;
  /// Point-to-point exchange: sends out[r] to each rank r in `out` and receives from each rank in
  /// `from` (both sides must agree); returns the received buffers by rank.
  std::map<int, Buffer> exchange(const std::map<int, Buffer>& out,
                                 const std::vector<int>& from) const;
  /// Bytes this rank has sent so far (point-to-point and its share of collectives) [B].
  std::int64_t bytes_sent() const { return bytes_sent_; }
  /// Messages this rank has sent so far [-].
  std::int64_t messages_sent() const { return messages_sent_; }

 private:
  Comm();
  int rank_ = 0, size_ = 1;
  mutable std::int64_t bytes_sent_ = 0, messages_sent_ = 0;
};

}  // namespace mpmcd::parallel
