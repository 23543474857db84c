#include "mpmcd/parallel/distribute.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <set>
#include <tuple>
#include <type_traits>

namespace mpmcd::parallel {

template <int Dim>
std::vector<int> deal_grains(const points::PointSet<Dim>& points,
                             const std::vector<points::Grain>& grains, Scheme scheme, int ranks) {
  std::vector<std::array<double, 2>> centroids(grains.size(), {0.0, 0.0});
  std::vector<double> count(grains.size(), 0.0), volume(grains.size(), 0.0);
  for (std::size_t g = 0; g < grains.size(); ++g) {
    for (std::int64_t p = grains[g].begin; p < grains[g].end; ++p) {
      for (int d = 0; d < std::min(Dim, 2); ++d) centroids[g][d] += points.x[p][d];
      volume[g] += points.volume[p];
    }
    count[g] = static_cast<double>(grains[g].size());
    if (grains[g].size() > 0)
      for (double& c : centroids[g]) c /= count[g];
  }
  return scheme == Scheme::kMaster ? deal_by_volume(volume, ranks)
                                   : bisection(centroids, count, ranks);
}

namespace {
// Appends / reads the committed state of grain g (PointSet::for_each_state_field, then history).
template <int Dim>
void put_grain(Buffer& b, const points::PointSet<Dim>& points,
               const std::vector<points::Grain>& grains, std::size_t g) {
  const std::int64_t h1 = g + 1 < grains.size() ? grains[g + 1].history_offset
                                                : static_cast<std::int64_t>(points.history.size());
  for (std::int64_t p = grains[g].begin; p < grains[g].end; ++p)
    points::PointSet<Dim>::for_each_state_field(points,
                                                [&](const auto& field) { b.put(field[p]); });
  for (std::int64_t k = grains[g].history_offset; k < h1; ++k) b.put(points.history[k]);
}
template <int Dim>
void get_grain(Buffer& b, points::PointSet<Dim>& points, const std::vector<points::Grain>& grains,
               std::size_t g) {
  const std::int64_t h1 = g + 1 < grains.size() ? grains[g + 1].history_offset
                                                : static_cast<std::int64_t>(points.history.size());
  for (std::int64_t p = grains[g].begin; p < grains[g].end; ++p)
    points::PointSet<Dim>::for_each_state_field(points, [&](auto& field) {
      field[p] = b.template get<typename std::decay_t<decltype(field)>::value_type>();
    });
  for (std::int64_t k = grains[g].history_offset; k < h1; ++k)
    points.history[k] = b.template get<double>();
}
}  // namespace

template <int Dim>
void gather_points(const Comm& comm, points::PointSet<Dim>& points,
                   const std::vector<points::Grain>& grains, const std::vector<int>& owner,
                   int root) {
  if (comm.size() == 1) return;
  Buffer mine;
  for (std::size_t g = 0; g < grains.size(); ++g)
    if (owner[g] == comm.rank()) put_grain(mine, points, grains, g);
  std::vector<std::vector<char>> all;
  if (root < 0) {
    all = comm.allgather(mine.bytes());
  } else {
    all = comm.gather(mine.bytes(), root);
    if (comm.rank() != root) return;
  }
  for (int r = 0; r < comm.size(); ++r) {
    if (r == comm.rank()) continue;
    Buffer b;
    b.bytes() = std::move(all[r]);
    for (std::size_t g = 0; g < grains.size(); ++g)
      if (owner[g] == r) get_grain(b, points, grains, g);
  }
}

template <int Dim>
contact::Problem<Dim> gather_contacts(const Comm& comm, const contact::Problem<Dim>& local,
                                      int root) {
  struct Row {
    std::int64_t node;
    std::int32_t body_a, grain_b, wall;
    double mass_a, mass_b;
    std::int64_t node_a;
    Vec<Dim> normal, wall_velocity, impulse;
    double gap, friction;
  };
  Buffer mine;
  for (const auto& c : local.contacts) {
    Row r{};
    const auto& sb = local.slots[c.b];
    r.node = sb.node;
    r.grain_b = sb.grain;
    r.mass_b = sb.mass;
    r.wall = c.wall;
    r.body_a = c.a >= 0 ? local.slots[c.a].grain : -1 - c.wall;
    r.mass_a = c.a >= 0 ? local.slots[c.a].mass : 0.0;
    r.node_a = c.a >= 0 ? local.slots[c.a].node : -1;
    r.normal = c.normal;
    r.wall_velocity = c.wall_velocity;
    r.impulse = c.impulse;
    r.gap = c.gap;
    r.friction = c.friction;
    mine.put(r);
  }
  std::vector<Row> rows;
  const auto read = [&](Buffer& b) {
    while (!b.done()) rows.push_back(b.get<Row>());
  };
  if (comm.size() == 1) {
    read(mine);
  } else {
    auto all = comm.gather(mine.bytes(), root);
    if (comm.rank() != root) return {};
    for (auto& bytes : all) {
      Buffer b;
      b.bytes() = std::move(bytes);
      read(b);
    }
  }
  std::stable_sort(rows.begin(), rows.end(), [](const Row& x, const Row& y) {
    return std::tie(x.node, x.body_a, x.grain_b) < std::tie(y.node, y.body_a, y.grain_b);
  });
  contact::Problem<Dim> p;
  p.dt = local.dt;
  p.law = local.law;
  for (const auto& r : rows) {
    contact::Contact<Dim> c;
    if (r.body_a >= 0) {
      c.a = static_cast<std::int32_t>(p.slots.size());
      contact::Slot<Dim> sa;
      sa.mass = r.mass_a;
      sa.grain = r.body_a;
      sa.node = r.node_a;
      p.slots.push_back(sa);
    }
    contact::Slot<Dim> sb;
    sb.mass = r.mass_b;
    sb.grain = r.grain_b;
    sb.node = r.node;
    c.b = static_cast<std::int32_t>(p.slots.size());
    p.slots.push_back(sb);
    c.wall = r.wall;
    c.normal = r.normal;
    c.wall_velocity = r.wall_velocity;
    c.impulse = r.impulse;
    c.gap = r.gap;
    c.friction = r.friction;
    p.contacts.push_back(c);
  }
  return p;
}

template contact::Problem<2> gather_contacts<2>(const Comm&, const contact::Problem<2>&, int);
template contact::Problem<3> gather_contacts<3>(const Comm&, const contact::Problem<3>&, int);

template <int Dim>
double rebalance(const Comm& comm, points::PointSet<Dim>& points,
                 const std::vector<points::Grain>& grains, std::vector<int>& owner,
                 const std::vector<double>& weights, double threshold, bool& moved) {
  moved = false;
  const std::size_t ng = grains.size();
  constexpr std::size_t K = kWorkPhases;
  if (weights.size() != K * ng)
    throw std::logic_error("rebalance: expected kWorkPhases weights per grain");
  // Weights and centroids of every grain (each rank fills its own; sums in rank order).
  std::vector<double> data((K + 2) * ng, 0.0);
  const std::size_t cx = K * ng;  // centroids after the weights
  for (std::size_t g = 0; g < ng; ++g) {
    if (owner[g] != comm.rank()) continue;
    for (std::size_t k = 0; k < K; ++k) data[K * g + k] = weights[K * g + k];
    for (std::int64_t p = grains[g].begin; p < grains[g].end; ++p)
      for (int d = 0; d < std::min(Dim, 2); ++d) data[cx + 2 * g + d] += points.x[p][d];
    for (int d = 0; d < 2; ++d)
      data[cx + 2 * g + d] /= static_cast<double>(std::max<std::int64_t>(grains[g].size(), 1));
  }
  comm.sum(data);
  const std::vector<double> w(data.begin(), data.begin() + static_cast<std::ptrdiff_t>(cx));
  const double before = imbalance(owner, w, comm.size(), K);
  if (before <= threshold || comm.size() == 1) return before;
  std::vector<std::array<double, 2>> c(ng);
  for (std::size_t g = 0; g < ng; ++g) c[g] = {data[cx + 2 * g], data[cx + 2 * g + 1]};
  const std::vector<int> next = bisection(c, w, comm.size(), K);
  std::map<int, Buffer> out;
  std::set<int> from;
  for (std::size_t g = 0; g < ng; ++g) {
    if (next[g] == owner[g]) continue;
    if (owner[g] == comm.rank()) put_grain(out[next[g]], points, grains, g);
    if (next[g] == comm.rank()) from.insert(owner[g]);
  }
  auto in = comm.exchange(out, std::vector<int>(from.begin(), from.end()));
  for (std::size_t g = 0; g < ng; ++g)
    if (next[g] != owner[g] && next[g] == comm.rank())
      get_grain(in.at(owner[g]), points, grains, g);
  moved = next != owner;
  owner = next;
  return before;
}

template double rebalance<2>(const Comm&, points::PointSet<2>&, const std::vector<points::Grain>&,
                             std::vector<int>&, const std::vector<double>&, double, bool&);
template double rebalance<3>(const Comm&, points::PointSet<3>&, const std::vector<points::Grain>&,
                             std::vector<int>&, const std::vector<double>&, double, bool&);

std::vector<StageTime> stage_report(const Comm& comm, const std::map<std::string, double>& totals) {
  // Every rank's totals, as "name\0value" records.
  Buffer mine;
  for (const auto& [name, t] : totals) {
    mine.put(static_cast<std::int32_t>(name.size()));
    mine.bytes().insert(mine.bytes().end(), name.begin(), name.end());
    mine.put(t);
  }
  const auto all = comm.allgather(mine.bytes());
  std::vector<std::map<std::string, double>> per(all.size());
  std::set<std::string> names;
  for (std::size_t r = 0; r < all.size(); ++r) {
    Buffer b;
    b.bytes() = all[r];
    while (!b.done()) {
      const auto n = static_cast<std::size_t>(b.get<std::int32_t>());
      std::string name(n, ' ');
      for (std::size_t i = 0; i < n; ++i) name[i] = b.get<char>();
      per[r][name] = b.get<double>();
      names.insert(name);
    }
  }
  const auto get = [&](std::size_t r, const std::string& k) {
    const auto it = per[r].find(k);
    return it == per[r].end() ? 0.0 : it->second;
  };
  // Stages that run mostly on one thread per rank (flag only: the measured share is
  // one_thread_fraction, from the time in threaded regions).
  const std::set<std::string> one_thread = {"contact.detect", "contact.solve", "comm.entries",
                                            "output"};
  std::vector<StageTime> rows;
  for (const auto& name : names) {
    StageTime s;
    s.name = name;
    s.nested = name.ends_with(".comm") || name == "contact.gs" || name == kThreadedStage;
    s.one_thread = one_thread.count(name) > 0 || name.ends_with(".comm");
    std::vector<double> t, work;
    for (std::size_t r = 0; r < per.size(); ++r) {
      t.push_back(get(r, name));
      // Work: the stage's time minus the communication (waiting) inside it.
      work.push_back(name.starts_with("comm.") || name.ends_with(".comm")
                         ? 0.0
                         : t.back() - get(r, name + ".comm"));
    }
    s.max = *std::max_element(t.begin(), t.end());
    s.min = *std::min_element(t.begin(), t.end());
    double sum = 0;
    for (double x : t) sum += x;
    s.mean = sum / static_cast<double>(t.size());
    std::sort(work.begin(), work.end());
    // Time in which one rank works alone in this stage (the others wait at its end); with one
    // rank the whole stage is that rank's (reported, not counted as serial).
    s.serial = work.size() > 1 ? work[work.size() - 1] - work[work.size() - 2] : 0.0;
    rows.push_back(s);
  }
  return rows;
}

std::string stage_report_csv(const std::vector<StageTime>& rows, double wall_seconds, int ranks,
                             int threads, long long steps, double bytes_per_rank_step,
                             const Comm::SoloReport& solo) {
  std::string out = "stage,max_s,mean_s,min_s,work_serial_s,nested,one_thread\n";
  double imbalance = 0;
  for (const auto& s : rows) {
    out += fmt::format("{},{:.6e},{:.6e},{:.6e},{:.6e},{},{}\n", s.name, s.max, s.mean, s.min,
                       s.serial, s.nested ? 1 : 0, s.one_thread ? 1 : 0);
    if (!s.nested) imbalance += s.serial;
  }
  const double w = std::max(wall_seconds, 1e-300);
  out += fmt::format("# ranks,{}\n# threads,{}\n# steps,{}\n# wall_s,{:.6e}\n", ranks, threads,
                     steps, wall_seconds);
  // The serial fraction is measured at every synchronisation (Comm::solo_report); the sum of
  // the stages' imbalances is a lower bound on it, kept for comparison.
  out += fmt::format("# one_rank_serial_fraction,{:.6e}\n# one_rank_serial_fraction_cpu,{:.6e}\n",
                     solo.solo_s / w, solo.solo_cpu_s / w);
  out += fmt::format("# stage_imbalance_fraction,{:.6e}\n", imbalance / w);
  out += fmt::format("# counted_serial_fraction,{:.6e}\n", solo.solo_work_fraction);
  out += fmt::format("# sync_wait_fraction,{:.6e}\n# syncs,{}\n# syncs_consistent,{}\n",
                     solo.wait_s / w, solo.syncs, solo.consistent ? 1 : 0);
  out += fmt::format("# one_thread_fraction,{:.6e}\n",
                     one_thread_fraction(rows, wall_seconds, threads, solo));
  out += fmt::format("# bytes_sent_per_rank_per_step,{:.6e}\n", bytes_per_rank_step);
  for (const auto& [site, secs] : solo.by_site)
    out += fmt::format("# solo_s_at,{},{:.6e}\n", site, secs);
  return out;
}

double one_thread_fraction(const std::vector<StageTime>& rows, double wall_seconds, int threads,
                           const Comm::SoloReport& solo) {
  if (threads <= 1 || wall_seconds <= 0) return 0.0;
  double threaded = 0;
  for (const auto& s : rows)
    if (s.name == kThreadedStage) threaded = s.mean;
  return std::clamp((wall_seconds - threaded - solo.wait_s) / wall_seconds, 0.0, 1.0);
}

template std::vector<int> deal_grains<2>(const points::PointSet<2>&,
                                         const std::vector<points::Grain>&, Scheme, int);
template std::vector<int> deal_grains<3>(const points::PointSet<3>&,
                                         const std::vector<points::Grain>&, Scheme, int);
template void gather_points<2>(const Comm&, points::PointSet<2>&, const std::vector<points::Grain>&,
                               const std::vector<int>&, int);
template void gather_points<3>(const Comm&, points::PointSet<3>&, const std::vector<points::Grain>&,
                               const std::vector<int>&, int);

}  // namespace mpmcd::parallel
