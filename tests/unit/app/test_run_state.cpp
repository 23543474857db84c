// The run state <-> checkpoint conversion (app/run_state): a model and a run state written to a
// checkpoint::State and restored give back every point, grain and counter bit for bit; the flat
// arrays are point-major, matrices row by row; a checkpoint that does not fit its input (another
// dimension, a material it lacks, a point outside the grid) is refused; restore_from_checkpoint
// reads a run back from a file. Also the energy ledger's sums and terms.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"

namespace app = mpmcd::app;
using mpmcd::Mat;
using mpmcd::Vec;

namespace {

// Two disks of gel in a box of two walls, nothing run.
mpmcd::io::Config pair_config() {
  return mpmcd::io::parse_config(
      "[grid]\norigin = [0.0, 0.0]\nextent = [0.02, 0.012]\ncell_size = 0.001\n"
      "[[materials]]\nname = \"gel\"\nlaw = \"neo_hookean\"\ndensity = 990.0\n"
      "lambda = 3e6\nmu = 1.5e6\n"
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.006, 0.005]\n"
      "radius = 0.0035\n[grains.initial]\nvelocity = [1.0, 0.0]\n"
      "[[grains]]\nshape = \"disk\"\nmaterial = \"gel\"\ncenter = [0.0135, 0.0055]\n"
      "radius = 0.0035\n"
      "[[walls]]\nname = \"floor\"\npoint = [0.0, 0.0012]\nnormal = [0.0, 1.0]\n"
      "velocity = [0.0, 0.5]\n"
      "[[walls]]\nname = \"left\"\npoint = [0.0015, 0.0]\nnormal = [1.0, 0.0]\n"
      "[time]\ndt = 2e-5\nend_time = 1e-3\n",
      "pair.toml");
}

// Distinct values in every point field, as after some steps.
void deform(mpmcd::mpm::Model<2>& model) {
  auto& p = model.points;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double s = 1e-3 * static_cast<double>(i + 1);
    p.v[i] += Vec<2>(s, -2 * s);
    p.L[i] << s, 2 * s, 3 * s, 4 * s;
    p.F[i] << 1 + s, 0.1 * s, -0.2 * s, 1 - s;
    p.sigma[i] << 5 * s, 6 * s, 6 * s, 7 * s;
    p.domain[i](0, 1) = 0.3 * s;
    p.sigma_zz[i] = 8 * s;
    p.volume[i] *= 1 + s;
  }
}

app::RunState<2> some_run_state(const mpmcd::mpm::Model<2>& model) {
  app::RunState<2> r;
  r.step = 123;
  r.time = 2.46e-3;
  r.dt = 5e-6;
  r.good_since_cut = 7;
  r.failed_steps = 3;
  r.newton_iterations = 456;
  r.next_vtu = 2.5e-3;
  r.next_csv = 2.47e-3;
  r.csv_rows = 124;
  r.vtu_times = {0.0, 1e-3, 2e-3};
  r.warm = {{5, 0, 1, Vec<2>(1.5, -2.5)}, {-3, -2, 0, Vec<2>(0.25, 0.125)}};
  r.wall_points = {Vec<2>(0.0, 0.00243), Vec<2>(0.0015, 0.0)};
  r.energy.wall_work = {1.25, -0.5};
  r.energy.energy0 = 3.5;
  r.energy.kinetic0 = 3.25;
  r.energy.contact_dissipation = 0.125;
  r.energy.transfer_dissipation = 0.0625;
  r.energy.stress_work = -0.75;
  r.energy.body_work = 0.03125;
  r.ranks = 2;
  r.scheme = "master";
  r.threads = 2;
  r.grain_owner = {1, 0};
  r.grain_work.assign(model.grains.size() * 4, 2.0);
  return r;
}

template <typename T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

}  // namespace

TEST(RunState, CheckpointRoundTripIsExact) {
  const auto cfg = pair_config();
  auto model = app::build_model(cfg);
  deform(model);
  const auto run = some_run_state(model);
  const auto s = app::to_checkpoint(cfg, model, run, "periodic");
  EXPECT_EQ(s.dim, 2);
  EXPECT_EQ(s.reason, "periodic");
  EXPECT_EQ(s.input_text, cfg.source_text);
  ASSERT_EQ(s.points(), model.points.size());

  const auto back = app::restore_model<2>(cfg, s, "pair_checkpoint.h5");
  const auto& p = model.points;
  const auto& q = back.points;
  ASSERT_EQ(q.size(), p.size());
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(q.x[i], p.x[i]);
    EXPECT_EQ(q.v[i], p.v[i]);
    EXPECT_EQ(q.L[i], p.L[i]);
    EXPECT_EQ(q.F[i], p.F[i]);
    EXPECT_EQ(q.sigma[i], p.sigma[i]);
    EXPECT_EQ(q.domain[i], p.domain[i]);
  }
  EXPECT_TRUE(same_bits(q.sigma_zz, p.sigma_zz));
  EXPECT_TRUE(same_bits(q.mass, p.mass));
  EXPECT_TRUE(same_bits(q.volume0, p.volume0));
  EXPECT_TRUE(same_bits(q.volume, p.volume));
  EXPECT_TRUE(same_bits(q.grain, p.grain));
  EXPECT_TRUE(same_bits(q.history, p.history));
  ASSERT_EQ(back.grains.size(), model.grains.size());
  for (std::size_t g = 0; g < model.grains.size(); ++g) {
    EXPECT_EQ(back.grains[g].begin, model.grains[g].begin);
    EXPECT_EQ(back.grains[g].end, model.grains[g].end);
    EXPECT_EQ(back.grains[g].material, model.grains[g].material);
    EXPECT_EQ(back.grains[g].half_width, model.grains[g].half_width);
    EXPECT_EQ(back.grains[g].history_offset, model.grains[g].history_offset);
  }

  const auto r = app::run_state_of<2>(s);
  EXPECT_EQ(r.step, run.step);
  EXPECT_EQ(r.time, run.time);
  EXPECT_EQ(r.dt, run.dt);
  EXPECT_EQ(r.good_since_cut, run.good_since_cut);
  EXPECT_EQ(r.failed_steps, run.failed_steps);
  EXPECT_EQ(r.newton_iterations, run.newton_iterations);
  EXPECT_EQ(r.next_vtu, run.next_vtu);
  EXPECT_EQ(r.next_csv, run.next_csv);
  EXPECT_EQ(r.csv_rows, run.csv_rows);
  EXPECT_TRUE(same_bits(r.vtu_times, run.vtu_times));
  ASSERT_EQ(r.warm.size(), run.warm.size());
  for (std::size_t k = 0; k < run.warm.size(); ++k) {
    EXPECT_EQ(r.warm[k].node, run.warm[k].node);
    EXPECT_EQ(r.warm[k].a, run.warm[k].a);
    EXPECT_EQ(r.warm[k].b, run.warm[k].b);
    EXPECT_EQ(r.warm[k].impulse, run.warm[k].impulse);
  }
  ASSERT_EQ(r.wall_points.size(), 2u);
  EXPECT_EQ(r.wall_points[0], run.wall_points[0]);
  EXPECT_EQ(r.wall_points[1], run.wall_points[1]);
  EXPECT_TRUE(same_bits(r.energy.wall_work, run.energy.wall_work));
  EXPECT_EQ(r.energy.energy0, run.energy.energy0);
  EXPECT_EQ(r.energy.kinetic0, run.energy.kinetic0);
  EXPECT_EQ(r.energy.contact_dissipation, run.energy.contact_dissipation);
  EXPECT_EQ(r.energy.transfer_dissipation, run.energy.transfer_dissipation);
  EXPECT_EQ(r.energy.stress_work, run.energy.stress_work);
  EXPECT_EQ(r.energy.body_work, run.energy.body_work);
  EXPECT_EQ(r.ranks, run.ranks);
  EXPECT_EQ(r.scheme, run.scheme);
  EXPECT_EQ(r.threads, run.threads);
  EXPECT_EQ(r.grain_owner, run.grain_owner);
  EXPECT_TRUE(same_bits(r.grain_work, run.grain_work));
}

TEST(RunState, FlatArraysArePointMajorAndRowByRow) {
  const auto cfg = pair_config();
  auto model = app::build_model(cfg);
  deform(model);
  const auto s = app::to_checkpoint(cfg, model, some_run_state(model), "end");
  const std::size_t i = 5;
  EXPECT_EQ(s.x[2 * i + 1], model.points.x[i][1]);
  EXPECT_EQ(s.F[4 * i + 1], model.points.F[i](0, 1));  // (p * dim + a) * dim + b, a = 0, b = 1
  EXPECT_EQ(s.F[4 * i + 2], model.points.F[i](1, 0));
  EXPECT_EQ(s.warm_impulse[3], 0.125);  // second impulse, y
  EXPECT_EQ(s.wall_point[1], 0.00243);
}

TEST(RunState, RefusesACheckpointThatDoesNotFitItsInput) {
  const auto cfg = pair_config();
  const auto model = app::build_model(cfg);
  const auto good = app::to_checkpoint(cfg, model, some_run_state(model), "end");
  auto s = good;
  s.dim = 3;
  EXPECT_THROW(app::restore_model<2>(cfg, s, "c.h5"), mpmcd::InputError);
  s = good;
  s.grain_material[1] = 1;  // the input has one material
  EXPECT_THROW(app::restore_model<2>(cfg, s, "c.h5"), mpmcd::InputError);
  s = good;
  s.x[0] = -1.0;  // outside the grid
  EXPECT_THROW(app::restore_model<2>(cfg, s, "c.h5"), mpmcd::InputError);
  s = good;
  s.warm_b[0] = 2;  // no grain 2
  EXPECT_THROW(app::restore_model<2>(cfg, s, "c.h5"), mpmcd::InputError);
  s = good;
  s.wall_point.resize(2);  // one wall, the input has two
  EXPECT_THROW(app::restore_model<2>(cfg, s, "c.h5"), mpmcd::InputError);
}

TEST(EnergyLedger, SumsTheWallsWorkAndClosesOnItsTerms) {
  mpmcd::mpm::Diagnostics<2> d0;
  d0.kinetic = 2.0;
  d0.elastic = 0.0;
  app::EnergyLedger<2> ledger(app::EnergyLedger<2>::start(1, d0));
  EXPECT_TRUE(ledger.active());
  std::vector<mpmcd::mpm::Wall<2>> walls(1);
  walls[0].velocity = Vec<2>(0.0, -2.0);
  mpmcd::mpm::StepStats st;
  st.wall_force = {{0.0, 3.0, 0.0}};  // the grains push the wall up, it moves down: W = 6 dt
  st.contact_work = 0.5;
  st.transfer_loss = 0.25;
  st.stress_work = -1.0;
  st.body_work = 0.125;
  ledger.add_step(st, walls, 0.5);
  EXPECT_EQ(ledger.sums().wall_work[0], 3.0);
  EXPECT_EQ(ledger.sums().contact_dissipation, 2.5);
  EXPECT_EQ(ledger.sums().transfer_dissipation, 0.25);
  mpmcd::mpm::Diagnostics<2> d;
  d.kinetic = 2.0;
  d.elastic = 1.0;
  const auto l = ledger.terms(d);
  EXPECT_EQ(l.walls, 3.0);
  EXPECT_EQ(l.change, 1.0);
  EXPECT_EQ(l.internal, 0.0);  // stress work 1 stored as elastic energy 1
  EXPECT_EQ(l.rest, 3.0 + 0.125 - 2.5 - 0.25 - 0.0 - 1.0);
  EXPECT_EQ(app::EnergyLedger<2>::csv_header(pair_config()),
            ",wall_floor_work,wall_left_work,body_work,energy_change,contact_dissipation,"
            "transfer_dissipation,internal_dissipation,energy_unaccounted");
  EXPECT_EQ(app::EnergyLedger<2>(app::EnergySums{}).csv_fields(d), "");  // no walls, no ledger
}

TEST(RunState, RestoresARunFromACheckpointFile) {
  const auto cfg = pair_config();
  auto model = app::build_model(cfg);
  deform(model);
  const auto run = some_run_state(model);
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("mpmcd_run_state_" + std::to_string(getpid()) + ".h5");
  mpmcd::checkpoint::write(app::to_checkpoint(cfg, model, run, "end"), path.string());
  const auto restored = app::restore_from_checkpoint(path.string());  // input from the file
  std::filesystem::remove(path);
  EXPECT_EQ(restored.config.source_text, cfg.source_text);
  EXPECT_EQ(restored.model.points.size(), model.points.size());
  EXPECT_EQ(restored.model.points.F.back(), model.points.F.back());
  EXPECT_EQ(restored.settings.contact.walls.size(), 2u);
  EXPECT_EQ(restored.run.time, run.time);
  EXPECT_EQ(restored.run.step, run.step);
  EXPECT_EQ(restored.path, path.string());
}
