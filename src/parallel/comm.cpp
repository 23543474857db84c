#include "mpmcd/parallel/comm.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <stdexcept>

#include <fmt/format.h>

#ifdef MPMCD_WITH_MPI
#include <mpi.h>
#endif

namespace mpmcd::parallel {

namespace {
bool g_finalized = false;

// Steady clock [s].
double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// Process CPU time [s].
double cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Global collectives between two folds of the recorded intervals (bounds the buffer: about 40
// synchronisations per time step, 12 bytes each).
constexpr std::int64_t kFoldEvery = 1 << 16;

// "file.cpp:line" of a synchronisation (the file name without its directories).
std::string site_name(const char* path, std::int32_t line) {
  const std::string file = path;
  return fmt::format("{}:{}", file.substr(file.find_last_of('/') + 1), line);
}
}  // namespace

// Brackets one synchronisation: arrival on construction, departure on destruction; global
// collectives fold the recorded intervals every kFoldEvery calls (the same call on every rank).
class SyncMark {
 public:
  SyncMark(const Comm& c, const std::source_location& at, bool global) : c_(c) {
    c_.arrive(at);
    if (global && c_.recording_ && ++c_.collectives_ % kFoldEvery == 0) c_.fold_syncs();
  }
  ~SyncMark() { c_.depart(); }
  SyncMark(const SyncMark&) = delete;
  SyncMark& operator=(const SyncMark&) = delete;

 private:
  const Comm& c_;
};

void Comm::record_syncs() const {
  recording_ = size_ > 1;
  work_.clear();
  work_cpu_.clear();
  units_.clear();
  pending_units_ = 0;
  line_.clear();
  file_.clear();
  collectives_ = 0;
  traced_ = 0;
  folded_ = SoloReport{};
  last_exit_ = now_s();
  last_exit_cpu_ = cpu_s();
}

void Comm::arrive(const std::source_location& at) const {
  if (!recording_) return;
  last_arrival_ = now_s();
  work_.push_back(last_arrival_ - last_exit_);
  work_cpu_.push_back(cpu_s() - last_exit_cpu_);
  units_.push_back(pending_units_);
  pending_units_ = 0;
  line_.push_back(static_cast<std::int32_t>(at.line()));
  file_.push_back(at.file_name());
}

void Comm::depart() const {
  if (!recording_) return;
  last_exit_ = now_s();
  last_exit_cpu_ = cpu_s();
  waited_ += last_exit_ - last_arrival_;
}

void Comm::fold_syncs() const {
#ifdef MPMCD_WITH_MPI
  const auto n = static_cast<std::int64_t>(work_.size());
  std::vector<std::int64_t> counts(static_cast<std::size_t>(size_));
  MPI_Allgather(&n, 1, MPI_INT64_T, counts.data(), 1, MPI_INT64_T, MPI_COMM_WORLD);
  if (std::adjacent_find(counts.begin(), counts.end(), std::not_equal_to<>()) != counts.end()) {
    folded_.consistent = false;
  } else {
    const bool root = rank_ == 0;
    const auto total = static_cast<std::size_t>(root ? n * size_ : 0);
    std::vector<double> all_w(total), all_c(total), all_u(total);
    std::vector<std::int32_t> all_l(total);
    const int cnt = static_cast<int>(n);
    MPI_Gather(work_.data(), cnt, MPI_DOUBLE, all_w.data(), cnt, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    MPI_Gather(work_cpu_.data(), cnt, MPI_DOUBLE, all_c.data(), cnt, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    MPI_Gather(units_.data(), cnt, MPI_DOUBLE, all_u.data(), cnt, MPI_DOUBLE, 0, MPI_COMM_WORLD);
    MPI_Gather(line_.data(), cnt, MPI_INT32_T, all_l.data(), cnt, MPI_INT32_T, 0, MPI_COMM_WORLD);
    // Largest minus second largest of the ranks' intervals before sync k.
    const auto solo = [&](const std::vector<double>& all, std::int64_t k) {
      double first = 0, second = 0;
      for (int r = 0; r < size_; ++r) {
        const double d = all[static_cast<std::size_t>(r * n + k)];
        second = std::max(second, std::min(first, d));
        first = std::max(first, d);
      }
      return first - second;
    };
    if (root && !trace_path_.empty()) write_trace(all_w, all_c, all_u, n);
    for (std::int64_t k = 0; root && k < n; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      for (int r = 0; r < size_; ++r)
        if (all_l[static_cast<std::size_t>(r * n + k)] != line_[ks]) folded_.consistent = false;
      const std::string site = site_name(file_[ks], line_[ks]);
      const double s = solo(all_w, k);
      folded_.solo_s += s;
      folded_.solo_cpu_s += solo(all_c, k);
      folded_.solo_units += solo(all_u, k);
      for (int r = 0; r < size_; ++r)
        folded_.total_units += all_u[static_cast<std::size_t>(r * n + k)];
      folded_.by_site[site] += s;
    }
  }
  folded_.syncs += n;
#endif
  work_.clear();
  work_cpu_.clear();
  units_.clear();
  line_.clear();
  file_.clear();
}

void Comm::trace_syncs(const std::string& path) const {
  trace_path_ = path;
}

void Comm::write_trace(const std::vector<double>& all_w, const std::vector<double>& all_c,
                       const std::vector<double>& all_u, std::int64_t n) const {
  const bool fresh = traced_ == 0;
  std::FILE* f = std::fopen(trace_path_.c_str(), fresh ? "w" : "a");
  if (f == nullptr)
    throw std::runtime_error(fmt::format("cannot write the synchronisation trace {}", trace_path_));
  if (fresh) {
    std::string head = "sync,site";
    for (const char* col : {"wall_s", "cpu_s", "units"})
      for (int r = 0; r < size_; ++r) head += fmt::format(",{}{}", col, r);
    std::fprintf(f, "%s\n", head.c_str());
  }
  for (std::int64_t k = 0; k < n; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    std::string row = fmt::format("{},{}", traced_ + k, site_name(file_[ks], line_[ks]));
    for (const auto* all : {&all_w, &all_c, &all_u})
      for (int r = 0; r < size_; ++r)
        row += fmt::format(",{:.9g}", (*all)[static_cast<std::size_t>(r * n + k)]);
    std::fprintf(f, "%s\n", row.c_str());
  }
  std::fclose(f);
  traced_ += n;
}

Comm::SoloReport Comm::solo_report() const {
  if (!recording_) return {};
  fold_syncs();
  SoloReport out = folded_;
#ifdef MPMCD_WITH_MPI
  // Totals to every rank: rank 0's solo time and consistency, the mean time in syncs.
  std::vector<double> v{out.solo_s, out.solo_cpu_s, out.consistent ? 0.0 : 1.0, out.solo_units,
                        out.total_units};
  MPI_Bcast(v.data(), 5, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  double waited = waited_;
  MPI_Allreduce(MPI_IN_PLACE, &waited, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  out.solo_s = v[0];
  out.solo_cpu_s = v[1];
  out.consistent = v[2] == 0.0;
  out.solo_units = v[3];
  out.total_units = v[4];
  out.wait_s = waited / size_;
#endif
  out.solo_work_fraction = out.total_units > 0 ? out.solo_units / out.total_units : 0.0;
  return out;
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

const Comm& Comm::alone() {
  static const Comm comm{AloneTag{}};
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

void Comm::barrier([[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1) return;
  SyncMark mark(*this, at, true);
  MPI_Barrier(MPI_COMM_WORLD);
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

void Comm::sum(std::vector<double>& values, [[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  SyncMark mark(*this, at, true);
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

void Comm::sum(std::vector<std::int64_t>& values, [[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  SyncMark mark(*this, at, true);
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(std::int64_t));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT64_T, MPI_SUM,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

void Comm::max(std::vector<double>& values, [[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  SyncMark mark(*this, at, true);
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(double));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_DOUBLE, MPI_MAX,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

void Comm::min(std::vector<std::int64_t>& values, [[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1 || values.empty()) return;
  SyncMark mark(*this, at, true);
  bytes_sent_ += static_cast<std::int64_t>(values.size() * sizeof(std::int64_t));
  ++messages_sent_;
  MPI_Allreduce(MPI_IN_PLACE, values.data(), static_cast<int>(values.size()), MPI_INT64_T, MPI_MIN,
                MPI_COMM_WORLD);
#else
  (void)values;
#endif
}

std::vector<std::vector<char>> Comm::allgather(const std::vector<char>& mine,
                                               [[maybe_unused]] std::source_location at) const {
  std::vector<std::vector<char>> out(static_cast<std::size_t>(size_));
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) {
    SyncMark mark(*this, at, true);
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

std::vector<std::vector<char>> Comm::gather(const std::vector<char>& mine, int root,
                                            std::source_location at) const {
  std::map<int, Buffer> out;
  std::vector<int> from;
  if (rank_ != root) {
    out[root].bytes() = mine;
  } else {
    for (int r = 0; r < size_; ++r)
      if (r != root) from.push_back(r);
  }
  auto in = exchange(out, from, at);
  if (rank_ != root) return {};
  std::vector<std::vector<char>> all(static_cast<std::size_t>(size_));
  for (auto& [r, b] : in) all[static_cast<std::size_t>(r)] = std::move(b.bytes());
  all[static_cast<std::size_t>(root)] = mine;
  return all;
}

void Comm::broadcast(std::vector<char>& bytes, int root,
                     [[maybe_unused]] std::source_location at) const {
#ifdef MPMCD_WITH_MPI
  if (size_ == 1) return;
  SyncMark mark(*this, at, true);
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

std::map<int, Buffer> Comm::exchange(const std::map<int, Buffer>& out, const std::vector<int>& from,
                                     [[maybe_unused]] std::source_location at) const {
  std::map<int, Buffer> in;
#ifdef MPMCD_WITH_MPI
  if (size_ > 1) {
    SyncMark mark(*this, at, false);
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
