// rig::sweep::load_sweep_config: the shipped sweep files load and mean what they
// say; malformed and inconsistent sweep files are refused with a message
// naming the file, the key, the value and what was expected.
#include "rig/sweep/sweep_config.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "config/error.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "vision/detectors.hpp"

namespace {

namespace fs = std::filesystem;
using rig::sweep::SweepConfig;
using rig::sweep::SweepConfigError;

const std::string kConfig = std::string(RIG_SOURCE_DIR) + "/config";

// A fresh folder for one test's files.
fs::path temp_dir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("sweep_config_test_" + std::to_string(::getpid())) / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string write_file(const fs::path& path, const std::string& content) {
  std::ofstream(path) << content;
  return path.string();
}

// The message of the SweepConfigError that loading `path` throws ("" if none).
std::string load_error(const std::string& path) {
  try {
    rig::sweep::load_sweep_config(path);
  } catch (const SweepConfigError& e) {
    return e.what();
  }
  return "";
}

// A valid sweep file naming the repository's simulated-rig configs by
// absolute path, so that it can be written anywhere.
std::string valid_sweep() {
  return "[plan]\n"
         "kind = \"grid\"\n"
         "x_mm = [0, 900, 100]\n"
         "y_mm = [140, 160, 10]\n"
         "\n"
         "[capture]\n"
         "camera = \"gige:127.0.0.1\"\n"
         "calibration = \"\"\n"
         "frames_per_position = 3\n"
         "\n"
         "[bench]\n"
         "url = \"modbus-tcp://127.0.0.1:1502\"\n"
         "profile = \"" +
         kConfig +
         "/benches/sim.toml\"\n"
         "speed_mm_s = 100\n"
         "\n"
         "[settle]\n"
         "dwell_ms = 0\n"
         "\n"
         "[faults]\n"
         "on_alarm = \"pause\"\n"
         "\n"
         "[target]\n"
         "layout = \"" +
         kConfig +
         "/targets/paper.toml\"\n"
         "\n"
         "[rig]\n"
         "file = \"" +
         kConfig +
         "/rigs/sim.toml\"\n"
         "\n"
         "[database]\n"
         "path = \"out/run.db\"\n"
         "\n"
         "[telemetry]\n"
         "publish = \"tcp://127.0.0.1:5556\"\n"
         "control = \"tcp://127.0.0.1:5557\"\n";
}

// `text` with the first occurrence of `from` replaced by `to` (which must exist).
std::string edit(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  if (at == std::string::npos) ADD_FAILURE() << "no \"" << from << "\" in the sweep file";
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(SweepConfigValid, TheBaseFileOfTheMalformedCasesLoads) {
  const fs::path dir = temp_dir("base");
  const SweepConfig c =
      rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", valid_sweep()));
  EXPECT_EQ(c.plan.size(), 10u * 3u);
  EXPECT_EQ(c.database_path, (dir / "out/run.db").string());  // relative to the sweep file
}

// ---- detectors -------------------------------------------------------------

TEST(SweepConfigDetect, EveryDetectorThatReadsTheFamilyByDefaultAndTheChosenOnesInRegistryOrder) {
  const fs::path dir = temp_dir("detect");
  const SweepConfig all =
      rig::sweep::load_sweep_config(write_file(dir / "all.toml", valid_sweep()));
  EXPECT_EQ(all.detectors, vision::detectors_for_family("rig4x4"));
  EXPECT_EQ(all.detectors.front(), "rig");
  const SweepConfig two = rig::sweep::load_sweep_config(write_file(
      dir / "two.toml", valid_sweep() + "\n[detect]\ndetectors = [\"apriltag:d2\", \"rig\"]\n"));
  // The measurer's order, whatever the file's: the primary (rig's) first.
  EXPECT_EQ(two.detectors, (std::vector<std::string>{"rig", "apriltag:d2"}));
  EXPECT_EQ(two.to_json()["detect"]["detectors"], nlohmann::json({"rig", "apriltag:d2"}));
}

// A target whose family none of the chosen detectors decodes is refused when
// the file is read, before anything connects to the bench, naming the key,
// the detector and those that would do.
TEST(SweepConfigDetect, ADetectorThatCannotReadTheTargetsFamilyIsRefusedNamingWhoCan) {
  const fs::path dir = temp_dir("detect-family");
  std::ifstream in(kConfig + "/targets/paper.toml");
  const std::string layout((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  write_file(dir / "aruco.toml", "family = \"aruco:DICT_6X6_250\"\n" + layout);
  const std::string base =
      edit(valid_sweep(), kConfig + "/targets/paper.toml", (dir / "aruco.toml").string());
  const std::string error =
      load_error(write_file(dir / "rig.toml", base + "\n[detect]\ndetectors = [\"rig\"]\n"));
  EXPECT_NE(error.find("detect.detectors"), std::string::npos) << error;
  EXPECT_NE(error.find("\"rig\" does not decode it"), std::string::npos) << error;
  EXPECT_NE(error.find("aruco:DICT_6X6_250"), std::string::npos) << error;
  EXPECT_NE(error.find("\"aruco:subpix\""), std::string::npos) << error;  // who can
  const std::string unknown = load_error(
      write_file(dir / "unknown.toml", base + "\n[detect]\ndetectors = [\"aruco:fast\"]\n"));
  EXPECT_NE(unknown.find("\"aruco:fast\" does not decode it"), std::string::npos) << unknown;
  const std::string twice = load_error(write_file(
      dir / "twice.toml", base + "\n[detect]\ndetectors = [\"aruco:none\", \"aruco:none\"]\n"));
  EXPECT_NE(twice.find("twice"), std::string::npos) << twice;
  // Without [detect], the family's own detectors: cv::aruco's four.
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "default.toml", base));
  EXPECT_EQ(c.detectors, (std::vector<std::string>{"aruco:none", "aruco:subpix", "aruco:contour",
                                                   "aruco:apriltag"}));
}

// ---- shipped sweep files --------------------------------------------------

TEST(SweepConfigShipped, CiIsTheSimulatedRigWithAFewHundredPositions) {
  const SweepConfig c = rig::sweep::load_sweep_config(kConfig + "/sweeps/ci.toml");
  EXPECT_EQ(c.plan.size(), 73u * 3u);
  EXPECT_EQ(c.frames_per_position, 3);
  ASSERT_TRUE(c.speed_mm_s.has_value());
  EXPECT_EQ(*c.speed_mm_s, 100);
  EXPECT_EQ(c.bench_url.transport, motion::BenchUrl::Transport::kTcp);
  EXPECT_EQ(c.bench_url.host, "127.0.0.1");
  EXPECT_EQ(c.bench_url.port, 1502);
  EXPECT_EQ(c.camera_spec, "gige:127.0.0.1");
  EXPECT_EQ(c.camera_calibration_path, "");
  EXPECT_EQ(c.camera.intrinsics().fx, vision::Camera::paper_default().intrinsics().fx);
  EXPECT_EQ(c.bench_profile_path, fs::path(kConfig + "/benches/sim.toml").lexically_normal());
  EXPECT_EQ(c.database_path,
            fs::path(std::string(RIG_SOURCE_DIR) + "/out/ci/run.db").lexically_normal().string());
  EXPECT_EQ(c.faults.on_alarm, rig::sweep::AlarmAction::kAbort);
  // Not given in the file: the profile's settle timeout.
  EXPECT_EQ(c.settle.timeout.count(), c.bench_profile.timing.settle_timeout_ms);
  EXPECT_EQ(c.target.markers.size(), 4u);
  // The geometry is the rig file's, and its text is stored with the run.
  const vision::RigGeometry rig = vision::RigGeometry::load(kConfig + "/rigs/sim.toml");
  EXPECT_EQ(c.geometry.T_bench_target.t, rig.T_bench_target.t);
  EXPECT_NE(c.rig_geometry_text.find("[camera_mount]"), std::string::npos);
  EXPECT_NE(c.sweep_file_text.find("kind = \"grid\""), std::string::npos);
}

TEST(SweepConfigShipped, PaperIsThe1939PositionProtocolOverTheXTravel) {
  const SweepConfig c = rig::sweep::load_sweep_config(kConfig + "/sweeps/paper.toml");
  EXPECT_EQ(c.plan.size(), 1939u);
  double x_min = 1e9, x_max = -1e9;
  for (const rig::sweep::PlanPosition& p : c.plan.positions()) {
    x_min = std::min(x_min, p.x_mm);
    x_max = std::max(x_max, p.x_mm);
  }
  EXPECT_EQ(x_min, c.bench_profile.soft_limits.x_min_mm);
  EXPECT_EQ(x_max, c.bench_profile.soft_limits.x_max_mm);
  // With the file's own geometry, every one of the ten distance classes of
  // 0.09 m from 0.10 to 1.00 m holds positions (~28 columns x 7 rows each).
  std::vector<int> per_class(10, 0);
  for (const rig::sweep::PlanPosition& p : c.plan.positions()) {
    const double d = c.geometry.distance_m(p.x_mm, p.y_mm);
    ++per_class[std::min(9, std::max(0, static_cast<int>(std::floor((d - 0.10) / 0.09))))];
  }
  for (int k = 0; k < 10; ++k)
    EXPECT_GE(per_class[k], 7 * 27) << "class " << k;
}

TEST(SweepConfigValid, APaperPlanWithoutRangesSpansTheProfilesSoftLimits) {
  const fs::path dir = temp_dir("paper_default");
  const std::string text =
      edit(valid_sweep(), "kind = \"grid\"\nx_mm = [0, 900, 100]\ny_mm = [140, 160, 10]",
           "kind = \"paper\"");
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", text));
  ASSERT_EQ(c.plan.size(), 1939u);
  const motion::SoftLimits& limits = c.bench_profile.soft_limits;
  EXPECT_EQ(c.plan.positions().front().x_mm, limits.x_min_mm);
  EXPECT_EQ(c.plan.positions().front().y_mm, limits.y_min_mm);
  EXPECT_EQ(c.plan.positions().back().x_mm, limits.x_max_mm);
  EXPECT_EQ(c.plan.positions().back().y_mm, limits.y_max_mm);
}

TEST(SweepConfigShipped, SmokeIsTwelvePositionsOfTwoFramesWithDefaultsElsewhere) {
  const SweepConfig c = rig::sweep::load_sweep_config(kConfig + "/sweeps/smoke.toml");
  EXPECT_EQ(c.plan.size(), 12u);
  EXPECT_EQ(c.frames_per_position, 2);
  // No [settle], [telemetry]; most of [capture] and [faults] absent: the documented defaults.
  EXPECT_EQ(c.settle.timeout.count(), c.bench_profile.timing.settle_timeout_ms);
  EXPECT_EQ(c.settle.dwell.count(), 0);
  EXPECT_EQ(c.telemetry.publish, "tcp://127.0.0.1:5556");
  EXPECT_EQ(c.telemetry.control, "tcp://127.0.0.1:5557");
  EXPECT_FALSE(c.telemetry.allow_remote);
  EXPECT_TRUE(c.durable_commits);
  EXPECT_TRUE(c.home_first);
  EXPECT_EQ(c.capture.retries, 2);
  EXPECT_EQ(c.grab_timeout.count(), 2000);
  EXPECT_EQ(c.faults.max_consecutive_failed_positions, 5);
  EXPECT_EQ(c.faults.link_retries, 3);
  EXPECT_EQ(c.faults.camera_reopen_timeout.count(), 10000);
  EXPECT_EQ(c.faults.camera_reopen_interval.count(), 500);
  EXPECT_EQ(c.capture.pixel_format, "Mono8");
  EXPECT_TRUE(c.capture.software_trigger);
  EXPECT_FALSE(c.capture.exposure_us.has_value());
  EXPECT_FALSE(c.frames_dir.has_value());
}

// The keys that bound reopening a lost camera: 0 turns it off; an interval
// of 0 would spin on the camera's control channel.
TEST(SweepConfigValid, TheCameraReopenKeysAreReadAndBounded) {
  const fs::path dir = temp_dir("camera_reopen");
  const std::string text =
      edit(valid_sweep(), "on_alarm = \"pause\"\n",
           "on_alarm = \"pause\"\ncamera_reopen_timeout_ms = 0\ncamera_reopen_interval_ms = 250\n");
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "off.toml", text));
  EXPECT_EQ(c.faults.camera_reopen_timeout.count(), 0);
  EXPECT_EQ(c.faults.camera_reopen_interval.count(), 250);
  const std::string zero_interval = edit(valid_sweep(), "on_alarm = \"pause\"\n",
                                         "on_alarm = \"pause\"\ncamera_reopen_interval_ms = 0\n");
  const std::string error = load_error(write_file(dir / "zero.toml", zero_interval));
  EXPECT_NE(error.find("faults.camera_reopen_interval_ms = 0"), std::string::npos) << error;
  const std::string negative = edit(valid_sweep(), "on_alarm = \"pause\"\n",
                                    "on_alarm = \"pause\"\ncamera_reopen_timeout_ms = -1\n");
  const std::string error2 = load_error(write_file(dir / "negative.toml", negative));
  EXPECT_NE(error2.find("faults.camera_reopen_timeout_ms = -1"), std::string::npos) << error2;
}

TEST(SweepConfigValid, TheComputeThreadsAreReadBoundedAndDefaultToTheMachinesThreads) {
  const fs::path dir = temp_dir("compute");
  const SweepConfig dflt =
      rig::sweep::load_sweep_config(write_file(dir / "default.toml", valid_sweep()));
  EXPECT_EQ(dflt.compute_threads, rig::sweep::default_compute_threads());
  EXPECT_GE(dflt.compute_threads, 1);
  const SweepConfig one = rig::sweep::load_sweep_config(
      write_file(dir / "one.toml", valid_sweep() + "\n[compute]\nthreads = 1\n"));
  EXPECT_EQ(one.compute_threads, 1);
  EXPECT_EQ(one.to_json()["compute"]["threads"], 1);
  for (const char* bad : {"0", "257", "1.5"}) {
    const std::string text = valid_sweep() + "\n[compute]\nthreads = " + bad + "\n";
    const std::string error = load_error(write_file(dir / "bad.toml", text));
    EXPECT_NE(error.find(std::string("compute.threads = ") + bad), std::string::npos) << error;
    EXPECT_NE(error.find("1..256"), std::string::npos) << error;
  }
  const std::string unknown = valid_sweep() + "\n[compute]\nthread = 2\n";
  const std::string error = load_error(write_file(dir / "unknown.toml", unknown));
  EXPECT_NE(error.find("compute.thread"), std::string::npos) << error;
}

TEST(SweepConfigValid, RelativePathsAreResolvedAgainstTheSweepFilesFolder) {
  const fs::path dir = temp_dir("relative");
  fs::create_directories(dir / "recorded");
  std::string text = edit(valid_sweep(), "camera = \"gige:127.0.0.1\"",
                          "camera = \"replay:recorded\"\nsave_frames = \"frames/run\"");
  text = edit(text, "speed_mm_s = 100", "speed_mm_s = 100\nhome_first = false");
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", text));
  EXPECT_EQ(c.camera_spec, "replay:" + (dir / "recorded").string());
  ASSERT_TRUE(c.frames_dir.has_value());
  EXPECT_EQ(*c.frames_dir, (dir / "frames/run").string());
  EXPECT_FALSE(c.home_first);
}

TEST(SweepConfigValid, TheSettleTimeoutCheckUsesTheProfilesSpeedWhenNoneIsGiven) {
  // Without speed_mm_s the profile's default (50 mm/s) applies: the 100 mm
  // steps of the grid take at least 2000 ms, so 1500 ms is refused...
  const fs::path dir = temp_dir("default_speed");
  std::string text = edit(valid_sweep(), "speed_mm_s = 100\n", "home_first = false\n");
  const std::string refused = edit(text, "dwell_ms = 0", "timeout_ms = 1500");
  EXPECT_NE(load_error(write_file(dir / "refused.toml", refused))
                .find("settle.timeout_ms = 1500: expected a timeout longer than the longest move "
                      "of the plan: 100 mm from position 0 to position 1 takes at least 2000 ms "
                      "at 50 mm/s"),
            std::string::npos);
  // ... and 2500 ms accepted.
  const std::string accepted = edit(text, "dwell_ms = 0", "timeout_ms = 2500");
  EXPECT_EQ(rig::sweep::load_sweep_config(write_file(dir / "accepted.toml", accepted))
                .settle.timeout.count(),
            2500);
}

// The shipped plans must give the detector something to detect: at every
// position the pose marker and its quiet zone (one cell, side / 6, of white
// around the border, which the detector needs) project inside the image.
// Checked on the distorted image and on the undistorted (pinhole) one,
// because k1 < 0 folds far off-axis points back into the image.
TEST(SweepConfigShipped, ThePoseMarkerIsInViewAtEveryPositionOfEveryShippedPlan) {
  for (const char* name : {"ci", "paper", "smoke"}) {
    const SweepConfig c = rig::sweep::load_sweep_config(kConfig + "/sweeps/" + name + ".toml");
    const vision::Camera& cam = c.camera;
    const vision::TargetMarker& marker = c.target.pose_marker();
    const Eigen::Vector3d centre(marker.centre_m.x(), marker.centre_m.y(), 0);
    // Half side s/2 grown by one cell s/6: a factor 4/3 from the centre.
    constexpr double kQuietZoneScale = 4.0 / 3.0;
    for (const rig::sweep::PlanPosition& p : c.plan.positions()) {
      const vision::Pose T = c.geometry.T_cam_target(p.x_mm, p.y_mm);
      for (const Eigen::Vector3d& corner : c.target.corners_m(marker)) {
        const Eigen::Vector3d q = T * (centre + kQuietZoneScale * (corner - centre));
        ASSERT_GT(q.z(), 0) << name;
        const Eigen::Vector2d px = cam.project(q);
        const Eigen::Vector2d pin(cam.intrinsics().fx * q.x() / q.z() + cam.intrinsics().cx,
                                  cam.intrinsics().fy * q.y() / q.z() + cam.intrinsics().cy);
        for (const Eigen::Vector2d& u : {px, pin}) {
          EXPECT_TRUE(u.x() >= 0 && u.x() <= cam.width_px() - 1 && u.y() >= 0 &&
                      u.y() <= cam.height_px() - 1)
              << name << " at (" << p.x_mm << ", " << p.y_mm << ") mm: corner at " << u.transpose();
        }
      }
    }
  }
}

TEST(SweepConfigShipped, TheExampleCsvPlanLoadsAsASweepPlan) {
  const fs::path dir = temp_dir("csv");
  const std::string text = edit(edit(valid_sweep(), "kind = \"grid\"", "kind = \"csv\""),
                                "x_mm = [0, 900, 100]\ny_mm = [140, 160, 10]\n",
                                "file = \"" + kConfig + "/plans/example.csv\"\n");
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", text));
  ASSERT_EQ(c.plan.size(), 13u);
  EXPECT_EQ(c.plan.positions()[12].x_mm, 50);
  EXPECT_EQ(c.plan.positions()[12].y_mm, 160);
}

TEST(SweepConfigValid, InlineRigTablesGiveTheSameGeometryAsTheRigFile) {
  const fs::path dir = temp_dir("inline");
  const std::string text = edit(valid_sweep(), "file = \"" + kConfig + "/rigs/sim.toml\"\n",
                                "[rig.camera_mount]\n"
                                "offset_mm = [0.0, 0.0, 0.0]\n"
                                "misalignment_deg = [0.3, -0.2, 0.5]\n"
                                "[rig.target]\n"
                                "origin_mm = [1000.0, 150.0, 0.0]\n"
                                "tilt_deg = [1.0, -1.5, 0.0]\n");
  const SweepConfig c = rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", text));
  const vision::RigGeometry file = vision::RigGeometry::load(kConfig + "/rigs/sim.toml");
  EXPECT_EQ(c.geometry.T_carriage_cam.R, file.T_carriage_cam.R);
  EXPECT_EQ(c.geometry.T_bench_target.t, file.T_bench_target.t);
  EXPECT_EQ(c.rig_geometry_path, "");
  // The stored text is a rig file: it loads back to the same geometry.
  const vision::RigGeometry back =
      vision::RigGeometry::load(write_file(dir / "rig.toml", c.rig_geometry_text));
  EXPECT_EQ(back.T_carriage_cam.R, file.T_carriage_cam.R);
  EXPECT_EQ(back.T_bench_target.R, file.T_bench_target.R);
}

TEST(SweepConfigValid, JsonHoldsEveryResolvedValue) {
  const fs::path dir = temp_dir("json");
  const SweepConfig c =
      rig::sweep::load_sweep_config(write_file(dir / "sweep.toml", valid_sweep()));
  const nlohmann::json j = c.to_json();
  EXPECT_EQ(j["plan"]["size"], 30);
  EXPECT_EQ(j["capture"]["frames_per_position"], 3);
  EXPECT_EQ(j["bench"]["speed_mm_s"], 100.0);
  EXPECT_EQ(j["settle"]["timeout_ms"], c.bench_profile.timing.settle_timeout_ms);
  EXPECT_EQ(j["database"]["path"], (dir / "out/run.db").string());
  EXPECT_EQ(j["faults"]["on_alarm"], "pause");
  EXPECT_EQ(j["camera"]["fx"], vision::Camera::paper_default().intrinsics().fx);
  EXPECT_EQ(j["capture"]["exposure_us"], nullptr);  // not given: the camera keeps its own
  EXPECT_EQ(j["capture"]["retries"], 2);
  EXPECT_EQ(j["capture"]["grab_timeout_ms"], 2000);
  EXPECT_EQ(j["bench"]["url"], "modbus-tcp://127.0.0.1:1502");
  EXPECT_EQ(j["telemetry"]["control"], "tcp://127.0.0.1:5557");
}

// ---- malformed and inconsistent sweep files -------------------------------

struct BadCase {
  BadCase(const char* name, std::string from, std::string to, std::string expected,
          bool prefix_only = false, std::string prepend = "")
      : name(name),
        from(std::move(from)),
        to(std::move(to)),
        expected(std::move(expected)),
        prefix_only(prefix_only),
        prepend(std::move(prepend)) {}
  const char* name;
  std::string from, to;  // edit of valid_sweep() (from = "" appends `to`)
  std::string expected;  // the message after "PATH: "
  bool prefix_only;      // the message continues with a quoted cause
  std::string prepend;   // top-level keys put before the first table
};

class SweepConfigMalformed : public ::testing::TestWithParam<BadCase> {};

TEST_P(SweepConfigMalformed, IsRefusedNamingFileKeyValueAndExpectation) {
  const BadCase& c = GetParam();
  const fs::path dir = temp_dir(c.name);
  // Files some cases point at.
  write_file(dir / "garbage.yaml", "this: is: not: a calibration\n");
  write_file(dir / "bad.csv", "x_mm,y_mm\n0,150\n10;150\n");
  write_file(dir / "bad_profile.toml", "name = \"no tables\"\n");
  write_file(dir / "outside.csv", "x_mm,y_mm\n0,150\n901,150\n");
  const std::string text =
      c.prepend + (c.from.empty() ? valid_sweep() + c.to : edit(valid_sweep(), c.from, c.to));
  const std::string path = write_file(dir / "sweep.toml", text);
  const std::string message = load_error(path);
  std::string expected = path + ": " + c.expected;
  for (auto at = expected.find("{dir}"); at != std::string::npos; at = expected.find("{dir}")) {
    expected.replace(at, 5, dir.string());
  }
  if (c.prefix_only) {
    EXPECT_EQ(message.substr(0, expected.size()), expected) << message;
  } else {
    EXPECT_EQ(message, expected);
  }
}

const std::string kProfile = "profile = \"" + kConfig + "/benches/sim.toml\"";
const std::string kGrid = "kind = \"grid\"\nx_mm = [0, 900, 100]\ny_mm = [140, 160, 10]";
const std::string kCaptureKeys =
    "camera, calibration, frames_per_position, software_trigger, pixel_format, exposure_us, "
    "gain, packet_size, inter_packet_delay_ns, grab_timeout_ms, retries, save_frames";

INSTANTIATE_TEST_SUITE_P(
    Cases, SweepConfigMalformed,
    ::testing::Values(
        BadCase{"unknown_key", "frames_per_position = 3", "frames_per_positon = 3",
                "capture.frames_per_positon = 3: unknown key (misspelt?); expected one of " +
                    kCaptureKeys},
        BadCase{"unknown_table", "[settle]", "[setle]",
                "setle = { dwell_ms = 0 }: unknown key (misspelt?); expected one of the tables "
                "[plan], [capture], [bench], [settle], [faults], [target], [detect], [rig], "
                "[database], [telemetry], [compute], [[estimator]]"},
        BadCase{"wrong_type", "frames_per_position = 3", "frames_per_position = \"3\"",
                "capture.frames_per_position = \"3\": expected an integer in 1..1000"},
        BadCase{"frames_zero", "frames_per_position = 3", "frames_per_position = 0",
                "capture.frames_per_position = 0: expected an integer in 1..1000"},
        BadCase{"negative_step", "x_mm = [0, 900, 100]", "x_mm = [0, 900, -5]",
                "plan.x_mm = [0, 900, -5]: expected [min, max, step] in mm with min <= max and "
                "step > 0"},
        BadCase{"min_above_max", "y_mm = [140, 160, 10]", "y_mm = [160, 140, 10]",
                "plan.y_mm = [160, 140, 10]: expected [min, max, step] in mm with min <= max "
                "and step > 0"},
        BadCase{"outside_soft_limits", "x_mm = [0, 900, 100]", "x_mm = [0, 950, 100]",
                "plan.x_mm = [0, 950, 100]: position 10 (x 950, y 140 mm) is outside; "
                "expected every position inside the bench's soft limits x 0..900 mm, y 0..300 "
                "mm"},
        BadCase{"y_outside_soft_limits", "y_mm = [140, 160, 10]", "y_mm = [290, 310, 10]",
                "plan.y_mm = [290, 310, 10]: position 20 (x 0, y 310 mm) is outside; expected "
                "every position inside the bench's soft limits x 0..900 mm, y 0..300 mm"},
        BadCase{"csv_outside_soft_limits", kGrid, "kind = \"csv\"\nfile = \"outside.csv\"",
                "plan.file = \"outside.csv\": position 1 (x 901, y 150 mm) is outside; expected "
                "every position inside the bench's soft limits x 0..900 mm, y 0..300 mm"},
        BadCase{"bad_csv", kGrid, "kind = \"csv\"\nfile = \"bad.csv\"",
                "plan.file = \"bad.csv\": it does not load: ", true},
        BadCase{"missing_csv", kGrid, "kind = \"csv\"\nfile = \"none.csv\"",
                "plan.file = \"none.csv\": {dir}/none.csv is not an existing file; expected the "
                "path of a CSV plan (x_mm,y_mm) (relative to the sweep file)"},
        BadCase{"csv_and_grid", "y_mm = [140, 160, 10]", "y_mm = [140, 160, 10]\nfile = \"x.csv\"",
                "plan.file = \"x.csv\": plan.file belongs to kind = \"csv\", not \"grid\"; "
                "expected exactly one kind of plan"},
        BadCase{"grid_without_y", "y_mm = [140, 160, 10]\n", "",
                "plan.y_mm: missing; expected [min, max, step] in mm with min <= max and step > 0"},
        BadCase{"paper_reversed", kGrid, "kind = \"paper\"\ny_mm = [165, 135]",
                "plan.y_mm = [165, 135]: expected [min, max] in mm with min < max"},
        BadCase{"paper_with_step", kGrid, "kind = \"paper\"\nx_mm = [0, 900, 10]",
                "plan.x_mm = [0, 900, 10]: expected [min, max] in mm with min < max"},
        BadCase{"paper_with_serpentine", kGrid, "kind = \"paper\"\nserpentine = false",
                "plan.serpentine = false: plan.serpentine belongs to kind = \"grid\", not "
                "\"paper\"; expected exactly one kind of plan"},
        BadCase{"speed_above_max", "speed_mm_s = 100", "speed_mm_s = 150",
                "bench.speed_mm_s = 150: expected a speed in (0, 100] mm/s (the profile's max)"},
        BadCase{"speed_zero", "speed_mm_s = 100", "speed_mm_s = 0",
                "bench.speed_mm_s = 0: expected a speed in (0, 100] mm/s (the profile's max)"},
        BadCase{"missing_calibration", "calibration = \"\"", "calibration = \"cam.yaml\"",
                "capture.calibration = \"cam.yaml\": {dir}/cam.yaml is not an existing file; "
                "expected the path of a camera calibration file (relative to the sweep file)"},
        BadCase{"bad_calibration", "calibration = \"\"", "calibration = \"garbage.yaml\"",
                "capture.calibration = \"garbage.yaml\": it does not load: ", true},
        BadCase{"bad_camera_spec", "camera = \"gige:127.0.0.1\"", "camera = \"usb:0\"",
                "capture.camera = \"usb:0\": expected a camera spec gige:ADDRESS | gige:ID | "
                "v4l2:PATH | replay:DIR"},
        BadCase{"empty_camera_spec", "camera = \"gige:127.0.0.1\"", "camera = \"gige:\"",
                "capture.camera = \"gige:\": expected a camera spec gige:ADDRESS | gige:ID | "
                "v4l2:PATH | replay:DIR"},
        BadCase{"bad_bench_url", "url = \"modbus-tcp://127.0.0.1:1502\"",
                "url = \"tcp://127.0.0.1:1502\"",
                "bench.url = \"tcp://127.0.0.1:1502\": it does not load: bench URL "
                "tcp://127.0.0.1:1502: expected modbus-tcp://HOST:PORT or "
                "modbus-rtu:///dev/DEVICE?baud=...; expected a valid bench URL"},
        BadCase{"bad_bench_port", "url = \"modbus-tcp://127.0.0.1:1502\"",
                "url = \"modbus-tcp://127.0.0.1:99999\"",
                "bench.url = \"modbus-tcp://127.0.0.1:99999\": it does not load: ", true},
        BadCase{"missing_url", "url = \"modbus-tcp://127.0.0.1:1502\"\n", "",
                "bench.url: missing; expected a bench URL modbus-tcp://HOST:PORT or "
                "modbus-rtu:///dev/DEVICE?baud=..."},
        BadCase{"bad_profile", kProfile, "profile = \"bad_profile.toml\"",
                "bench.profile = \"bad_profile.toml\": it does not load: ", true},
        BadCase{"identical_telemetry", "control = \"tcp://127.0.0.1:5557\"",
                "control = \"tcp://127.0.0.1:5556\"",
                "telemetry.control = \"tcp://127.0.0.1:5556\": expected an endpoint different "
                "from telemetry.publish (tcp://127.0.0.1:5556)"},
        BadCase{"remote_telemetry", "publish = \"tcp://127.0.0.1:5556\"",
                "publish = \"tcp://0.0.0.0:5556\"",
                "telemetry.publish = \"tcp://0.0.0.0:5556\": endpoint \"tcp://0.0.0.0:5556\" "
                "binds beyond this machine (host \"0.0.0.0\")",
                true},
        BadCase{"not_really_loopback_telemetry", "publish = \"tcp://127.0.0.1:5556\"",
                "publish = \"tcp://127.evil.example:5556\"",
                "telemetry.publish = \"tcp://127.evil.example:5556\": endpoint "
                "\"tcp://127.evil.example:5556\" binds beyond this machine",
                true},
        BadCase{"bad_on_alarm", "on_alarm = \"pause\"", "on_alarm = \"ignore\"",
                "faults.on_alarm = \"ignore\": expected \"pause\" or \"abort\""},
        BadCase{"unknown_kind", "kind = \"grid\"", "kind = \"spiral\"",
                "plan.kind = \"spiral\": expected \"grid\", \"csv\" or \"paper\""},
        BadCase{"missing_table", "[database]\npath = \"out/run.db\"\n", "",
                "database: missing; expected a table [database]"},
        BadCase{"settle_timeout_too_short", "dwell_ms = 0", "timeout_ms = 1000",
                "settle.timeout_ms = 1000: expected a timeout longer than the longest move of "
                "the plan: 140 mm from home (x 0, y 0 mm) to position 0 takes at least 1400 ms "
                "at 100 mm/s"},
        BadCase{"not_a_table", "[settle]\ndwell_ms = 0\n", "",
                "settle = 3: expected a table [settle]", false, "settle = 3\n"},
        BadCase{"rig_file_and_tables", "[database]",
                "[rig.target]\norigin_mm = [1000, 150, 0]\n"
                "tilt_deg = [0, 0, 0]\n[database]",
                "rig.file = \"" + kConfig +
                    "/rigs/sim.toml\": inline rig tables are given too; "
                    "expected exactly one of rig.file = \"RIG.toml\" or the tables "
                    "[rig.camera_mount] and [rig.target]"},
        BadCase{"rig_missing", "file = \"" + kConfig + "/rigs/sim.toml\"", "",
                "rig.file: missing; expected exactly one of rig.file = \"RIG.toml\" or the tables "
                "[rig.camera_mount] and [rig.target]"},
        BadCase{
            "inline_rig_unknown_key", "file = \"" + kConfig + "/rigs/sim.toml\"",
            "[rig.camera_mount]\noffset_mm = [0, 0, 0]\nmisalignment_deg = [0, 0, 0]\n"
            "tilt_deg = [0, 0, 0]\n[rig.target]\norigin_mm = [1000, 150, 0]\ntilt_deg = [0, 0, 0]",
            "rig.camera_mount.tilt_deg = [0, 0, 0]: unknown key (misspelt?); expected one of "
            "offset_mm, misalignment_deg"},
        BadCase{"inline_rig_short_vector", "file = \"" + kConfig + "/rigs/sim.toml\"",
                "[rig.camera_mount]\noffset_mm = [0, 0]\nmisalignment_deg = [0, 0, 0]\n"
                "[rig.target]\norigin_mm = [1000, 150, 0]\ntilt_deg = [0, 0, 0]",
                "rig.camera_mount.offset_mm = [0, 0]: expected [x, y, z], three finite numbers"},
        BadCase{"target_behind_camera", "file = \"" + kConfig + "/rigs/sim.toml\"",
                "[rig.camera_mount]\noffset_mm = [0, 0, 0]\nmisalignment_deg = [0, 0, 0]\n"
                "[rig.target]\norigin_mm = [500, 150, 0]\ntilt_deg = [0, 0, 0]",
                "rig.target = ", true},
        BadCase{"missing_layout", "/targets/paper.toml", "/targets/none.toml",
                "target.layout = \"" + kConfig + "/targets/none.toml\": ", true},
        BadCase{"bad_pixel_format", "frames_per_position = 3",
                "frames_per_position = 3\npixel_format = \"RGB8\"",
                "capture.pixel_format = \"RGB8\": expected \"Mono8\", \"Mono10\", \"Mono12\", "
                "\"Mono12Packed\", \"Mono16\" or \"BayerRG8\""},
        BadCase{"packet_size_too_large", "frames_per_position = 3",
                "frames_per_position = 3\npacket_size = 16000",
                "capture.packet_size = 16000: expected a GigE Vision packet size in bytes, an "
                "integer 576..9000 (1500 on a standard MTU; more needs jumbo frames)"},
        BadCase{"negative_inter_packet_delay", "frames_per_position = 3",
                "frames_per_position = 3\ninter_packet_delay_ns = -5",
                "capture.inter_packet_delay_ns = -5: expected a GigE Vision inter-packet delay in "
                "ns, 0..1e8"},
        BadCase{"missing_replay_folder", "camera = \"gige:127.0.0.1\"",
                "camera = \"replay:frames\"",
                "capture.camera = \"replay:frames\": {dir}/frames is not a folder; expected "
                "replay:DIR with an existing folder"},
        BadCase{"database_is_a_folder", "path = \"out/run.db\"", "path = \".\"",
                "database.path = \".\": {dir}/ is a folder; expected the path of the run database "
                "file"},
        BadCase{"save_frames_is_a_file", "frames_per_position = 3",
                "frames_per_position = 3\nsave_frames = \"bad.csv\"",
                "capture.save_frames = \"bad.csv\": {dir}/bad.csv exists and is not a folder; "
                "expected a folder path, or \"\""},
        BadCase{"negative_dwell", "dwell_ms = 0", "dwell_ms = -1",
                "settle.dwell_ms = -1: expected an integer in 0..3600000"},
        BadCase{"toml_syntax", "frames_per_position = 3", "frames_per_position = = 3",
                "line 9, column 23: ", true}));

TEST(SweepConfigFile, AFolderOrAMissingFileIsRefusedAsTheSweepFile) {
  const fs::path dir = temp_dir("folder");
  EXPECT_EQ(load_error(dir.string()),
            dir.string() + ": is a folder; expected the sweep file, a regular file");
  EXPECT_EQ(load_error((dir / "none.toml").string()),
            (dir / "none.toml").string() + ": does not exist; expected the sweep file");
}

TEST(SweepConfigFile, ItsErrorsAreConfigErrors) {
  EXPECT_THROW(rig::sweep::load_sweep_config("/nonexistent/sweep.toml"), config::ConfigError);
}

}  // namespace

namespace {

TEST(SweepConfigEstimators, ShippedExternalSweepRunsTheExampleFromTheRepository) {
  const SweepConfig c = rig::sweep::load_sweep_config(kConfig + "/sweeps/external.toml");
  ASSERT_EQ(c.estimators.size(), 1u);
  const rig::estimator::EstimatorSpec& e = c.estimators[0];
  EXPECT_EQ(e.solver_name(), "ext:opencv_pnp");
  EXPECT_EQ(e.command, (std::vector<std::string>{"../../examples/solvepnp_estimator.py"}));
  EXPECT_EQ(e.working_dir, kConfig + "/sweeps");  // where the relative script path holds
  EXPECT_EQ(e.timeout.count(), 2000);
  EXPECT_EQ(e.startup_timeout.count(), 10000);
  EXPECT_EQ(e.max_restarts, 3);
  EXPECT_TRUE(e.send_corners);
  EXPECT_EQ(c.to_json()["estimators"][0]["solver"], "ext:opencv_pnp");
  // No [[estimator]]: none.
  EXPECT_TRUE(rig::sweep::load_sweep_config(kConfig + "/sweeps/smoke.toml").estimators.empty());
}

TEST(SweepConfigEstimators, EveryKeyIsCheckedNamingFileKeyAndExpectation) {
  const fs::path dir = temp_dir("estimators");
  const std::string file = (dir / "sweep.toml").string();
  const auto error_of = [&](const std::string& tables) {
    return load_error(write_file(file, valid_sweep() + "\n" + tables));
  };
  const std::string ok = "[[estimator]]\nname = \"a\"\ncommand = [\"python3\"]\n";
  EXPECT_EQ(error_of(ok), "");
  EXPECT_EQ(error_of(ok + "[[estimator]]\nname = \"a\"\ncommand = [\"python3\"]\n"),
            file +
                ": estimator[1].name = \"a\": used twice; expected a name no other "
                "[[estimator]] has");
  EXPECT_EQ(error_of("[[estimator]]\nname = \"a b\"\ncommand = [\"python3\"]\n"),
            file +
                ": estimator[0].name = \"a b\": expected a name of 1..64 characters A-Z a-z "
                "0-9 _ . -");
  EXPECT_EQ(error_of("[[estimator]]\nname = \"a\"\n"),
            file +
                ": estimator[0].command: missing; expected the command as an array of 1..256 "
                "strings, program first");
  EXPECT_EQ(error_of("[[estimator]]\nname = \"a\"\ncommand = \"python3 x.py\"\n"),
            file +
                ": estimator[0].command = \"python3 x.py\": expected the command as an array "
                "of 1..256 strings, program first");
  EXPECT_EQ(error_of("[[estimator]]\nname = \"a\"\ncommand = [\"no-such-estimator-program\"]\n"),
            file +
                ": estimator[0].command = [\"no-such-estimator-program\"]: "
                "\"no-such-estimator-program\" is not an executable file on PATH; expected "
                "the command as an array of 1..256 strings, program first");
  EXPECT_NE(
      error_of("[[estimator]]\nname = \"a\"\ncommand = [\"./missing.py\"]\n")
          .find("\"./missing.py\" is not an executable file (relative to " + dir.string() + ")"),
      std::string::npos);
  EXPECT_EQ(error_of(ok + "timeout_ms = 0\n"),
            file + ": estimator[0].timeout_ms = 0: expected an integer in 1..600000");
  EXPECT_EQ(error_of(ok + "max_restarts = -1\n"),
            file + ": estimator[0].max_restarts = -1: expected an integer in 0..1000");
  EXPECT_NE(error_of(ok + "timout_ms = 5\n").find("estimator[0].timout_ms = 5: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("[estimator]\nname = \"a\"\n").find("estimator"), std::string::npos);
}

}  // namespace
