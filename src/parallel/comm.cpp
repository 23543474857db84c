#include "mpmcd/parallel/comm.hpp"

#include <algorithm>
#include <stdexcept>

#ifdef MPMCD_WITH_MPI
#include <mpi.h>
#endif

namespace mpmcd::parallel {

namespace {
bool g_finalized = false;
}

Comm::Comm() {
#ifdef MPMCD_WITH_MPI
  int init = 0;
  MPI_Initialized(&init);
  if (!init) {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
#endif
}

Comm& Comm::world() {
  static Comm comm;
  return comm;
}

void Comm::finalize() {
#ifdef MPMCD_WITH_MPI
  int init = 0, fin = 0;
  MPI_Initialized(&init);
  MPI_Finalized(&fin);
  if (init && !fin && !g_finalized) MPI_Finalize();
#endif
  g_finalized = true;
}

void Comm::abort(int code) const {
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  (void)code;
}

bool Comm::has_mpi() {
#ifdef MPMCD_WITH_MPI
  return true;
#else
  return false;
#endif
}

void Comm::barrier() const {
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) MPI_Barrier(MPI_COMM_WORLD);
#endif
}

namespace {
#ifdef MPMCD_WITH_MPI
// All ranks' copies of `values` (rank-major).
template <class T>
std::vector<T> gather_all(const std::vector<T>& values, int size, MPI_Datatype type) {
  std::vector<T> all(values.size() * static_cast<std::size_t>(size));
  MPI_Allgather(values.data(), static_cast<int>(values.size()), type, all.data(),
                static_cast<int>(values.size()), type, MPI_COMM_WORLD);
  return all;
}
#endif
}  // namespace

void Comm::sum(std::vector<double>& values) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(double));
  ++messages_sent_;
  const auto all = gather_all(values, size_, MPI_DOUBLE);
  const std::size_t n = values.size();
  for (std::size_t i = 0; i < n; ++i) {
    double s = 0;  // rank order: the same sum on every rank and in every run
    for (int r = 0; r < size_; ++r) s += all[r * n + i];
    values[i] = s;
  }
#else
  (void)values;
#endif
}

void Comm::sum(std::vector<std::int64_t>& values) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(std::int64_t));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT64_T, MPI_SUM,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

void Comm::max(std::vector<double>& values) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(double));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

void Comm::min(std::vector<std::int64_t>& values) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(std::int64_t));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT64_T, MPI_MIN,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

std::vector<std::vector<char>> Comm::allgather(const std::vector<char>& mine) const {
  std::vector<std::vector<char>> out(static_cast<std::size_t>(size_));
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) {
    bytes_sent_ += static_cast<std::int64_t>(mine.size());
    ++messages_sent_;
    int n = static_cast<int>(mine.size());
    std::vector<int> counts(size_), displs(size_);
    MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
    int total = 0;
    for (int r = 0; r < size_; ++r) {
      displs[r] = total;
      total += counts[r];
    }
    std::vector<char> all(static_cast<std::size_t>(total));
    MPI_Allgatherv(mine.data(), n, MPI_CHAR, all.data(), counts.data(), displs.data(), MPI_CHAR,
                   MPI_COMM_WORLD);
    for (int r = 0; r < size_; ++r)
      out[r].assign(all.begin() + displs[r], all.begin() + displs[r] + counts[r]);
    return out;
  }
#endif
  out[0] = mine;
  return out;
}

void Comm::broadcast(std::vector<char>& bytes, int root) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1) return;
  std::int64_t n = static_cast<std::int64_t>(bytes.size());
  if (rank_ == root) {
    bytes_sent_ += n;
    ++messages_sent_;
  }
  MPI_Bcast(&n, 1, MPI_INT64_T, root, MPI_COMM_WORLD);
  bytes.resize(static_cast<std::size_t>(n));
  MPI_Bcast(bytes.data(), static_cast<int>(n), MPI_CHAR, root, MPI_COMM_WORLD);
#else
  (void)bytes;
  (void)root;
#endif
}

std::map<int, Buffer> Comm::exchange(const std::map<int, Buffer>& out,
                                     const std::vector<int>& from) const {
  std::map<int, Buffer> in;
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) {
    // Sizes first, then the payloads (tags 1 and 2); all requests non-blocking.
    std::vector<MPI_Request> req;
    std::vector<std::int64_t> out_n, in_n(from.size());
    out_n.reserve(out.size());
    for (const auto& [r, b] : out) out_n.push_back(static_cast<std::int64_t>(b.bytes().size()));
    req.reserve(2 * (out.size() + from.size()));
    for (std::size_t i = 0; i < from.size(); ++i) {
      req.emplace_back();
      MPI_Irecv(&in_n[i], 1, MPI_INT64_T, from[i], 1, MPI_COMM_WORLD, &req.back());
    }
    std::size_t k = 0;
    for (const auto& [r, b] : out) {
      req.emplace_back();
      MPI_Isend(&out_n[k++], 1, MPI_INT64_T, r, 1, MPI_COMM_WORLD, &req.back());
    }
    MPI_Waitall(static_cast<int>(req.size()), req.data(), MPI_STATUSES_IGNORE);
    req.clear();
    for (std::size_t i = 0; i < from.size(); ++i) {
      auto& buf = in[from[i]].bytes();
      buf.resize(static_cast<std::size_t>(in_n[i]));
      req.emplace_back();
      MPI_Irecv(buf.data(), static_cast<int>(in_n[i]), MPI_CHAR, from[i], 2, MPI_COMM_WORLD,
                &req.back());
    }
    for (const auto& [r, b] : out) {
      req.emplace_back();
      MPI_Isend(b.bytes().data(), static_cast<int>(b.bytes().size()), MPI_CHAR, r, 2,
                MPI_COMM_WORLD, &req.back());
      bytes_sent_ += static_cast<std::int64_t>(b.bytes().size() + sizeof(std::int64_t));
      messages_sent_ += 2;
    }
    MPI_Waitall(static_cast<int>(req.size()), req.data(), MPI_STATUSES_IGNORE);
    return in;
  }
#endif
  for (int r : from) {
    if (r != rank_) throw std::logic_error("Comm::exchange: no other rank in a serial run");
    in[r] = out.at(r);
  }
  return in;
}

}  // namespace mpmcd::parallel
