// The run state <-> checkpoint conversion (app/run_state): a model, its warm start and the energy
// ledger's sums written to a checkpoint::State and restored give back every value bit for bit; the
// flat arrays are point-major, matrices row by row; a checkpoint that does not fit its input
// (another dimension, a material it lacks, a point outside the grid) is refused;
// restore_from_checkpoint reads a run back from a file. Also the energy ledger's sums and terms.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "mpmcd/app/energy_ledger.hpp"
#include "mpmcd/app/model_builder.hpp"
#include "mpmcd/app/run_state.hpp"
#include "mpmcd/checkpoint/checkpoint.hpp"
#include "mpmcd/core/errors.hpp"
#include "mpmcd/io/load_config.hpp"
#include "mpmcd/walls/wall.hpp"

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

// Warm-start impulses (a grain-grain contact, a face contact with wall 1) and walls as after
// some steps.
std::vector<mpmcd::mpm::WarmImpulse<2>> some_warm_start() {
  return {{5, 0, 1, Vec<2>(1.5, -2.5)}, {-3, -2, 0, Vec<2>(0.25, 0.125)}};
}

std::vector<mpmcd::walls::Wall<2>> walls_of(const mpmcd::io::Config& cfg,
                                            const mpmcd::mpm::Model<2>& model) {
  return app::build_settings(cfg, model).contact.walls;
}

// The checkpoint of `model` at t = 2.46e-3 s.
mpmcd::checkpoint::State checkpoint_of(const mpmcd::io::Config& cfg,
                                       const mpmcd::mpm::Model<2>& model) {
  mpmcd::checkpoint::State s;
  s.time = 2.46e-3;
  s.dt = 2e-5;
  s.step = 123;
  s.grain_owner.assign(model.grains.size(), 0);
  s.grain_work.assign(model.grains.size() * 4, 0.0);
  app::store_energy(app::EnergyLedger<2>::start(cfg.walls.size(), mpmcd::mpm::diagnostics(model)),
                    s);
  app::store_run(cfg, model, some_warm_start(), walls_of(cfg, model), s);
  return s;
}

}  // namespace

TEST(RunState, CheckpointRoundTripIsExact) {
  const auto cfg = pair_config();
  auto model = app::build_model(cfg);
  deform(model);
  const auto s = checkpoint_of(cfg, model);
  EXPECT_EQ(s.dim, 2);
  EXPECT_EQ(s.input_text, cfg.source_text);
  ASSERT_EQ(s.points(), model.points.size());

  // The restored model, warm start and ledger sums stored again give the same checkpoint, to
  // the last bit of every array (the payload checksum covers them all).
  auto back = app::restore_model<2>(cfg, s, "pair_checkpoint.h5");
  ASSERT_EQ(back.points.size(), model.points.size());
  ASSERT_EQ(back.grains.size(), model.grains.size());
  auto again = s;
  app::store_energy(app::energy_sums_of(s), again);
  app::store_run(cfg, back, app::warm_start_of<2>(s), walls_of(cfg, back), again);
  EXPECT_EQ(mpmcd::checkpoint::payload_checksum(again), mpmcd::checkpoint::payload_checksum(s));
  back.points.F[3](0, 1) = std::nextafter(back.points.F[3](0, 1), 2.0);  // one bit off: seen
  app::store_run(cfg, back, app::warm_start_of<2>(s), walls_of(cfg, back), again);
  EXPECT_NE(mpmcd::checkpoint::payload_checksum(again), mpmcd::checkpoint::payload_checksum(s));

  const auto warm = app::warm_start_of<2>(s);
  const auto sent = some_warm_start();
  ASSERT_EQ(warm.size(), sent.size());
  for (std::size_t k = 0; k < sent.size(); ++k) {
    EXPECT_EQ(warm[k].node, sent[k].node);
    EXPECT_EQ(warm[k].a, sent[k].a);
    EXPECT_EQ(warm[k].b, sent[k].b);
    EXPECT_EQ(warm[k].impulse, sent[k].impulse);
  }

  app::EnergySums e;
  e.wall_work = {1.25, -0.5};
  e.energy0 = 3.5;
  e.kinetic0 = 3.25;
  e.contact_dissipation = 0.125;
  e.transfer_dissipation = 0.0625;
  e.stress_work = -0.75;
  e.body_work = 0.03125;
  mpmcd::checkpoint::State t;
  app::store_energy(e, t);
  EXPECT_EQ(t.wall_work, e.wall_work);
  EXPECT_EQ(t.kinetic0, 3.25);
  EXPECT_EQ(t.transfer_dissipation, 0.0625);
  auto u = t;
  app::store_energy(app::energy_sums_of(t), u);
  EXPECT_EQ(mpmcd::checkpoint::payload_checksum(u), mpmcd::checkpoint::payload_checksum(t));
}

TEST(RunState, FlatArraysArePointMajorAndRowByRow) {
  const auto cfg = pair_config();
  auto model = app::build_model(cfg);
  deform(model);
  const auto s = checkpoint_of(cfg, model);
  const std::size_t i = 5;
  EXPECT_EQ(s.x[2 * i + 1], model.points.x[i][1]);
  EXPECT_EQ(s.F[4 * i + 1], model.points.F[i](0, 1));  // (p * dim + a) * dim + b, a = 0, b = 1
  EXPECT_EQ(s.F[4 * i + 2], model.points.F[i](1, 0));
  EXPECT_EQ(s.warm_impulse[3], 0.125);                 // second impulse, y
  EXPECT_EQ(s.wall_point[1], 0.0012 + 2.46e-3 * 0.5);  // the floor moves up at 0.5 m/s
}

TEST(RunState, RefusesACheckpointThatDoesNotFitItsInput) {
  const auto cfg = pair_config();
  const auto model = app::build_model(cfg);
  const auto good = checkpoint_of(cfg, model);
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
  std::vector<mpmcd::walls::Wall<2>> walls(1);
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
  const std::filesystem::path path = std::filesystem::temp_directory_path() /
                                     ("mpmcd_run_state_" + std::to_string(getpid()) + ".h5");
  mpmcd::checkpoint::write(checkpoint_of(cfg, model), path.string());
  const auto restored = app::restore_from_checkpoint(path.string());  // input from the file
  std::filesystem::remove(path);
  EXPECT_EQ(restored.config.source_text, cfg.source_text);
  EXPECT_EQ(restored.model.points.size(), model.points.size());
  EXPECT_EQ(restored.model.points.F.back(), model.points.F.back());
  EXPECT_EQ(restored.settings.contact.walls.size(), 2u);
  EXPECT_EQ(restored.state.time, 2.46e-3);
  EXPECT_EQ(restored.state.step, 123);
  EXPECT_EQ(restored.warm.size(), 2u);
  EXPECT_EQ(restored.path, path.string());
}
