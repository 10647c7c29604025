// `rig sweep --replay` end to end: the real `rig sweep` saves
// frames from the simulated rig (real Modbus TCP, real GigE Vision on
// loopback), then the real `rig sweep --replay` measures them again into new
// runs of the same database, with no bench or camera.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <tuple>

#include "db/store/sha256.hpp"
#include "db/store/store.hpp"
#include "rig/sweep/frame_files.hpp"
#include "sim_rig_fixture.hpp"

namespace {

namespace fs = std::filesystem;

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

using rig_test::SimRig;
using rig_test::SqlProbe;
using rig_test::SweepFileOptions;

// Every estimate of a run, by (plan index, frame index, solver, scope).
using EstimateKey = std::tuple<std::int64_t, int, std::string, std::string>;
std::map<EstimateKey, db::store::EstimateRecord> estimates_of(const db::store::Store& store,
                                                              std::int64_t run) {
  std::map<EstimateKey, db::store::EstimateRecord> out;
  for (const std::string& solver : store.solvers(run))
    for (const db::store::EstimateRow& row : store.estimates(run, solver))
      out[{row.plan_index, row.frame_index, solver, row.estimate.scope}] = row.estimate;
  return out;
}

TEST(SweepReplay, ReplaysSavedFramesIntoANewRunWithIdenticalResultsAndFailsChangedFrames) {
  SimRig rig;
  SweepFileOptions o;
  o.plan = "kind = \"grid\"\nx_mm = [400.0, 600.0, 100.0]\ny_mm = [150.0, 150.0, 10.0]\n";
  o.extra_capture = "save_frames = \"" + rig.file("frames") + "\"\n";
  const std::string sweep = rig.write_sweep(o);  // 3 positions x 2 frames
  const rig_test::RigRun recorded = rig_test::run_rig("sweep " + sweep + " --no-progress");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.out << recorded.err;

  // The frames are on disk where the run says, with the hashes it stored.
  {
    SqlProbe db(rig.database());
    const auto rows = db.column(
        "SELECT f.image_path || ' ' || f.image_sha256 FROM frames f JOIN positions p ON "
        "p.id = f.position_id WHERE p.run_id = 1 ORDER BY p.plan_index, f.frame_index");
    ASSERT_EQ(rows.size(), 6u);
    for (const std::string& row : rows) {
      const std::string path = row.substr(0, row.find(' '));
      EXPECT_EQ(fs::path(path).parent_path(),
                rig::sweep::run_frames_folder(rig.file("frames"), rig.database(), 1))
          << row;
      EXPECT_EQ(db::store::sha256_hex(file_bytes(path)), row.substr(row.find(' ') + 1)) << row;
    }
  }

  const rig_test::RigRun replay = rig_test::run_rig("sweep " + sweep + " --replay 1 --no-progress");
  ASSERT_EQ(replay.exit_code, 0) << replay.out << replay.err;
  EXPECT_NE(replay.out.find("rig sweep: run 2 completed"), std::string::npos) << replay.out;
  {
    db::store::StoreOptions read_only;
    read_only.read_only = true;
    const db::store::Store store(rig.database(), read_only);
    const db::store::Run run2 = store.run(2);
    EXPECT_EQ(run2.status, db::store::RunStatus::kCompleted);
    const auto config = nlohmann::json::parse(run2.description.config_json);
    EXPECT_EQ(config["replay_of"]["run"], 1);
    EXPECT_EQ(config["replay_of"]["database"], fs::absolute(rig.database()).string());
    EXPECT_EQ(run2.description.plan_json, store.run(1).description.plan_json);

    // Same positions, read-backs and truths: the replay bench reports the
    // recorded read-back and the truth is the same geometry at it.
    const auto p1 = store.positions(1);
    const auto p2 = store.positions(2);
    ASSERT_EQ(p1.size(), 3u);
    ASSERT_EQ(p2.size(), p1.size());
    for (std::size_t i = 0; i < p1.size(); ++i) {
      EXPECT_EQ(p2[i].plan_index, p1[i].plan_index);
      EXPECT_EQ(p2[i].status, db::store::PositionStatus::kOk);
      EXPECT_EQ(p2[i].commanded_x_mm, p1[i].commanded_x_mm);
      EXPECT_EQ(p2[i].measured_x_mm, p1[i].measured_x_mm);
      EXPECT_EQ(p2[i].measured_y_mm, p1[i].measured_y_mm);
      EXPECT_EQ(p2[i].true_distance_m, p1[i].true_distance_m);
    }
    // The same pixels through the same deterministic detector and solvers:
    // the same estimates. The PNG is lossless, so the only room is the
    // floating-point evaluation order, which does not change between two runs
    // of one binary; 1e-12 relative is a few thousand ulps of slack.
    const auto e1 = estimates_of(store, 1);
    const auto e2 = estimates_of(store, 2);
    EXPECT_EQ(e1.size(), e2.size());
    EXPECT_GE(e1.size(), 6u * 2u);  // every frame, every solver, two scopes
    for (const auto& [key, a] : e1) {
      const auto it = e2.find(key);
      ASSERT_NE(it, e2.end()) << std::get<2>(key) << " " << std::get<3>(key);
      const db::store::EstimateRecord& b = it->second;
      EXPECT_EQ(b.converged, a.converged) << std::get<2>(key);
      EXPECT_NEAR(b.distance_m, a.distance_m, 1e-12 * std::abs(a.distance_m))
          << std::get<0>(key) << " " << std::get<1>(key) << " " << std::get<2>(key) << " "
          << std::get<3>(key);
      EXPECT_NEAR(b.reprojection_error_px, a.reprojection_error_px,
                  1e-12 * std::max(1.0, std::abs(a.reprojection_error_px)))
          << std::get<2>(key);
    }
    // Each replayed frame names its PNG as source; none is saved again.
    const db::store::PositionRecord full = store.position(2, 1);
    ASSERT_EQ(full.frames.size(), 2u);
    EXPECT_EQ(full.frames[0].source, *store.position(1, 1).frames[0].image_path);
    EXPECT_FALSE(full.frames[0].image_path.has_value());
    EXPECT_FALSE(fs::exists(rig::sweep::run_frames_folder(rig.file("frames"), rig.database(), 2)));
  }

  // A PNG changed after the run: its position fails in the replay, naming
  // the file; the others are measured.
  const std::string changed = SqlProbe(rig.database())
                                  .value(
                                      "SELECT f.image_path FROM frames f JOIN positions p ON "
                                      "p.id = f.position_id WHERE p.run_id = 1 AND "
                                      "p.plan_index = 1 AND f.frame_index = 1");
  std::ofstream(changed, std::ios::binary | std::ios::app) << '\0';
  const rig_test::RigRun tampered =
      rig_test::run_rig("sweep " + sweep + " --replay 1 --no-progress");
  EXPECT_EQ(tampered.exit_code, 0) << tampered.out << tampered.err;
  SqlProbe db(rig.database());
  EXPECT_EQ(db.value("SELECT status FROM runs WHERE id = 3"), "completed");
  EXPECT_EQ(db.column("SELECT plan_index || ' ' || status FROM positions WHERE run_id = 3 "
                      "ORDER BY plan_index"),
            (std::vector<std::string>{"0 ok", "1 failed", "2 ok"}));
  const std::string reason =
      db.value("SELECT failure_reason FROM positions WHERE run_id = 3 AND plan_index = 1");
  EXPECT_EQ(reason.rfind("camera: ", 0), 0u) << reason;
  EXPECT_NE(reason.find("recorded frame " + changed + " has SHA-256"), std::string::npos) << reason;

  // Errors, each before a run is created.
  const long long runs = db.count("SELECT count(*) FROM runs");
  const rig_test::RigRun both = rig_test::run_rig("sweep " + sweep + " --replay 1 --resume 1");
  EXPECT_EQ(both.exit_code, 2);
  EXPECT_NE(both.err.find("--replay 1 and --resume 1 together"), std::string::npos) << both.err;
  const rig_test::RigRun retry_replay =
      rig_test::run_rig("sweep " + sweep + " --replay 1 --retry-failed");
  EXPECT_EQ(retry_replay.exit_code, 2);
  EXPECT_NE(retry_replay.err.find("--retry-failed without --resume"), std::string::npos)
      << retry_replay.err;
  const rig_test::RigRun unknown = rig_test::run_rig("sweep " + sweep + " --replay 9");
  EXPECT_EQ(unknown.exit_code, 2);
  EXPECT_NE(unknown.err.find("--replay 9: "), std::string::npos) << unknown.err;
  const rig_test::RigRun of_replay = rig_test::run_rig("sweep " + sweep + " --replay 2");
  EXPECT_EQ(of_replay.exit_code, 2);
  EXPECT_NE(of_replay.err.find("saved no frames: it is a replay of run 1"), std::string::npos)
      << of_replay.err;
  o.frames = 3;
  const rig_test::RigRun more =
      rig_test::run_rig("sweep " + rig.write_sweep(o, "three.toml") + " --replay 1");
  EXPECT_EQ(more.exit_code, 2);
  EXPECT_NE(more.err.find("capture.frames_per_position = 3 but run 1 of"), std::string::npos)
      << more.err;
  const rig_test::RigRun resume_replay = rig_test::run_rig("sweep " + sweep + " --resume 3");
  EXPECT_EQ(resume_replay.exit_code, 2);
  EXPECT_NE(resume_replay.err.find("run 3 is a replay"), std::string::npos) << resume_replay.err;
  EXPECT_EQ(SqlProbe(rig.database()).count("SELECT count(*) FROM runs"), runs);
}

}  // namespace
