// Two single-axis drives as one XY bench (DriveProfile::axis_drives,
// TwoDriveBench; docs/drive-profile.md): the real driver against
// tests/motion/axis_drives.py (pymodbus), which serves an X drive and a Y drive
// of different maps and conventions, at two unit ids on one port or on two
// ports, with a link drop on the Y drive on SIGUSR1.
//
// Positions are exact: each emulated drive moves in whole counts (X 0.01 mm,
// Y 1 um) and stops on the target count, and the driver quantizes a target to
// the same counts, so a settled read-back equals the target to within the
// rounding of the mm <-> counts conversion (1e-9 mm).
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <signal.h>

#include <chrono>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "drive_emulator.hpp"
#include "motion/drive_profile.hpp"
#include "motion/errors.hpp"
#include "motion/two_drive_bench.hpp"

namespace {

using namespace std::chrono_literals;
using motion_test::kEmulatorStart;
using motion_test::kExact;
using motion_test::kSettle;
using rig_test::ChildProcess;

std::string profile_path() {
  return std::string(RIG_SOURCE_DIR) + "/tests/motion/axis_drives.toml";
}

class TwoDrives : public ::testing::Test {
 protected:
  // Starts the emulator with `args` ({"--two-ports"}, {"--drop-s", "10"}).
  void start(const std::vector<std::string>& args = {}) {
    std::vector<std::string> argv = {"/usr/bin/python3",
                                     std::string(RIG_SOURCE_DIR) + "/tests/motion/axis_drives.py"};
    argv.insert(argv.end(), args.begin(), args.end());
    drives_ = std::make_unique<ChildProcess>(argv);
    const auto line = drives_->read_line(kEmulatorStart);
    ASSERT_TRUE(line && line->rfind("PORTS ", 0) == 0)
        << "two-drive emulator did not start (python3-pymodbus installed?)";
    std::istringstream ports(line->substr(6));
    ports >> x_port_ >> y_port_;
  }
  static std::string url(int port) { return "modbus-tcp://127.0.0.1:" + std::to_string(port); }
  // One port: both drives at the bench URL with their unit ids.
  std::unique_ptr<motion::TwoDriveBench> connect_one_port() {
    return std::make_unique<motion::TwoDriveBench>(motion::BenchUrl::parse(url(x_port_)), profile_);
  }
  // Two ports: the Y drive's own url; the X drive at the bench URL.
  std::unique_ptr<motion::TwoDriveBench> connect_two_ports() {
    auto drives = std::make_shared<motion::AxisDrives>(*profile_.axis_drives);
    drives->y.url = motion::BenchUrl::parse(url(y_port_));
    profile_.axis_drives = drives;
    return std::make_unique<motion::TwoDriveBench>(motion::BenchUrl::parse(url(x_port_)), profile_);
  }
  void set_y_reconnect_timeout(int ms) {
    auto drives = std::make_shared<motion::AxisDrives>(*profile_.axis_drives);
    drives->y.drive.timing.reconnect_timeout_ms = ms;
    profile_.axis_drives = drives;
  }
  // `n` registers of `table` at `address` of unit `unit` on `port`, read
  // with libmodbus directly.
  static std::vector<std::uint16_t> raw(int port, int unit, bool input, int address, int n) {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port);
    modbus_set_slave(ctx, unit);
    std::vector<std::uint16_t> regs(n);
    EXPECT_EQ(modbus_connect(ctx), 0);
    const int got = input ? modbus_read_input_registers(ctx, address, n, regs.data())
                          : modbus_read_registers(ctx, address, n, regs.data());
    EXPECT_EQ(got, n);
    modbus_close(ctx);
    modbus_free(ctx);
    return regs;
  }
  static void expect_at(const motion::BenchStatus& s, double x, double y) {
    EXPECT_NEAR(s.position.x_mm, x, kExact);
    EXPECT_NEAR(s.position.y_mm, y, kExact);
    EXPECT_TRUE(s.in_position);
    EXPECT_FALSE(s.moving);
  }

  std::unique_ptr<ChildProcess> drives_;
  int x_port_ = 0, y_port_ = 0;
  motion::DriveProfile profile_ = motion::load_drive_profile(profile_path());
};

TEST_F(TwoDrives, TwoUnitsOnOnePortHomeMoveAndSettleTogether) {
  start();
  auto bench = connect_one_port();
  bench->home();
  const motion::BenchStatus home = bench->wait_settled(kSettle);
  expect_at(home, 0, 0);
  EXPECT_TRUE(home.homed);
  bench->move_to(123.45, 67.891);
  expect_at(bench->wait_settled(kSettle), 123.45, 67.891);
  bench->move_to(10, 90);
  expect_at(bench->wait_settled(kSettle), 10, 90);

  // Each drive holds its axis in its own convention: X at unit 1, low word
  // first in 0.01 mm; Y at unit 2, high word first in um, its control word
  // cleared by the drive.
  EXPECT_EQ(raw(x_port_, 1, false, 0x100, 2), (std::vector<std::uint16_t>{1000, 0}));
  EXPECT_EQ(raw(x_port_, 2, false, 0x10, 4),
            (std::vector<std::uint16_t>{1, 90000 - 65536, 1000, 0}));
  EXPECT_EQ(raw(x_port_, 2, true, 0x20, 2), (std::vector<std::uint16_t>{1, 90000 - 65536}));
  EXPECT_EQ(bench->reconnects(), 0);
}

TEST_F(TwoDrives, AnAlarmOnOneAxisNamesItAndStopsTheOther) {
  start();
  auto bench = connect_one_port();
  bench->home();
  bench->wait_settled(kSettle);
  // 120 mm is inside the bench's soft limits but beyond the Y drive's own
  // travel (0..100 mm): the Y drive raises its overtravel alarm 0x31, while
  // the X drive starts its 150 mm move (1.5 s).
  bench->move_to(150, 120);
  try {
    bench->wait_settled(kSettle);
    FAIL() << "an overtravel alarm of the Y drive went unreported";
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), 0x31);
    EXPECT_EQ(e.meaning(), "Y: overtravel");
    EXPECT_NE(std::string(e.what()).find(
                  url(x_port_) + "?unit=2 (Y axis drive): alarm 49 (Y: overtravel) at 0 mm"),
              std::string::npos)
        << e.what();
  }
  // The X drive was stopped on the Y drive's alarm, short of its target; the
  // X drive itself shows no alarm.
  const motion::BenchStatus x = bench->x_drive().status();
  EXPECT_FALSE(x.moving);
  EXPECT_FALSE(x.alarm);
  EXPECT_LT(x.position.x_mm, 150);
  const motion::BenchStatus both = bench->status();
  EXPECT_TRUE(both.alarm);
  EXPECT_EQ(both.alarm_code, 0x31);
  EXPECT_EQ(both.alarm_meaning, "Y axis: Y: overtravel");

  bench->reset_alarm();
  EXPECT_FALSE(bench->status().alarm);
  bench->move_to(40, 50);
  expect_at(bench->wait_settled(kSettle), 40, 50);
}

TEST_F(TwoDrives, ALinkDropOnTheYPortIsRiddenOutOnThatAxisAlone) {
  start({"--two-ports", "--drop-s", "0.3"});
  auto bench = connect_two_ports();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(100, 80);  // 1 s on X, 0.8 s on Y at 100 mm/s: the drop falls inside
  drives_->signal(SIGUSR1);
  expect_at(bench->wait_settled(kSettle), 100, 80);
  EXPECT_GE(bench->y_drive().reconnects(), 1);
  EXPECT_EQ(bench->x_drive().reconnects(), 0);
}

TEST_F(TwoDrives, AYUnitThatStopsAnsweringOnASharedPortIsRiddenOut) {
  start({"--drop-s", "0.3"});
  auto bench = connect_one_port();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(100, 80);
  drives_->signal(SIGUSR1);
  expect_at(bench->wait_settled(kSettle), 100, 80);
  EXPECT_GE(bench->y_drive().reconnects(), 1);
  EXPECT_EQ(bench->x_drive().reconnects(), 0);
}

TEST_F(TwoDrives, AYLinkThatStaysDownRaisesALinkErrorNamingTheYDrive) {
  start({"--two-ports", "--drop-s", "30"});
  set_y_reconnect_timeout(300);
  auto bench = connect_two_ports();
  drives_->signal(SIGUSR1);
  try {
    // The drop takes effect within milliseconds; 3 s of polling bounds it.
    for (int i = 0; i < 600; ++i) {
      bench->status();
      std::this_thread::sleep_for(5ms);
    }
    FAIL() << "the Y link never went down";
  } catch (const motion::BenchLinkError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bench " + url(y_port_) + " (Y axis drive): link down during status"),
              std::string::npos)
        << what;
  }
  // The X drive answers on.
  EXPECT_NO_THROW(bench->x_drive().status());
}

TEST_F(TwoDrives, ASpeedOneDriveRefusesIsTakenByNeither) {
  start();
  auto bench = connect_one_port();
  bench->home();
  bench->wait_settled(kSettle);
  // 0.04 mm/s is 4 units of the X drive's 0.01 mm/s, but rounds to 0 units
  // of the Y drive's 0.1 mm/s: refused for the Y drive, so for the bench.
  try {
    bench->set_speed(0.04);
    FAIL() << "a speed the Y drive cannot take was accepted";
  } catch (const motion::SoftLimitError& e) {
    EXPECT_NE(std::string(e.what()).find(url(x_port_) +
                                         "?unit=2 (Y axis drive): speed 0.04 mm/s rounds to 0"),
              std::string::npos)
        << e.what();
  }
  // Both drives keep the profile's 100 mm/s: the next move writes it to each
  // (X: 10000 x 0.01 mm/s, Y: 1000 x 0.1 mm/s). Had X taken 0.04 mm/s, this
  // 1 mm move would take 25 s and time out.
  bench->move_to(1, 1);
  expect_at(bench->wait_settled(kSettle), 1, 1);
  EXPECT_EQ(raw(x_port_, 1, false, 0x102, 1)[0], 10000);
  EXPECT_EQ(raw(x_port_, 2, false, 0x12, 1)[0], 1000);
}

TEST_F(TwoDrives, AMoveOutsideTheBenchLimitsSendsNothingToEitherDrive) {
  start();
  auto bench = connect_one_port();
  EXPECT_THROW(bench->move_to(50, 151), motion::SoftLimitError);
  EXPECT_THROW(bench->move_to(201, 50), motion::SoftLimitError);
  EXPECT_EQ(raw(x_port_, 1, false, 0x100, 2), (std::vector<std::uint16_t>{0, 0}));
  EXPECT_EQ(raw(x_port_, 2, false, 0x10, 2), (std::vector<std::uint16_t>{0, 0}));
}

TEST(TwoDriveProfile, ABenchUrlNamingOneUnitIsRefusedForTwoDrives) {
  const motion::DriveProfile p = motion::load_drive_profile(profile_path());
  try {
    motion::TwoDriveBench bench(motion::BenchUrl::parse("modbus-tcp://127.0.0.1:1?unit=3"), p);
    FAIL();
  } catch (const motion::ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find("?unit=3 names one unit for the two drives"),
              std::string::npos)
        << e.what();
  }
}

// The profile text with `from` replaced by `to` (once), parsed.
std::string error_of(const std::string& from, const std::string& to) {
  std::ifstream in(profile_path());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  text.replace(at, from.size(), to);
  try {
    motion::parse_drive_profile(text, "two.toml");
  } catch (const motion::ProfileError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(TwoDriveProfile, ItsDrivesAreReadWithTheBenchsMotionAndLimits) {
  const motion::DriveProfile p = motion::load_drive_profile(profile_path());
  ASSERT_TRUE(p.axis_drives);
  const motion::DriveProfile& x = p.axis_drives->x.drive;
  const motion::DriveProfile& y = p.axis_drives->y.drive;
  EXPECT_EQ(x.axis, 'x');
  EXPECT_EQ(y.axis, 'y');
  EXPECT_EQ(x.unit_id, 1);
  EXPECT_EQ(y.unit_id, 2);
  EXPECT_EQ(x.word_order, motion::WordOrder::kLowFirst);
  EXPECT_EQ(y.word_order, motion::WordOrder::kHighFirst);
  EXPECT_EQ(y.registers.feedback, motion::RegisterTable::kInput);
  EXPECT_EQ(y.protocol.handshake, motion::CommandHandshake::kSelfClearing);
  EXPECT_EQ(y.soft_limits.x_max_mm, 150);  // the bench's Y limits, as the Y drive's axis
  EXPECT_EQ(x.soft_limits.x_max_mm, 200);
  EXPECT_EQ(y.alarm_meaning(0x31), "Y: overtravel");
  EXPECT_EQ(y.timing.settle_time_ms, 10);
  EXPECT_FALSE(p.axis_drives->x.url);
}

TEST(TwoDriveProfile, ShippedTemplateLoads) {
  const motion::DriveProfile p = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/template_two_drives.toml");
  ASSERT_TRUE(p.axis_drives);
  EXPECT_EQ(p.axis_drives->x.drive.unit_id, 1);
  EXPECT_EQ(p.axis_drives->y.drive.unit_id, 2);
}

// The drive-family profiles load and say what their header says (they are
// driven against an emulator of their semantics in drive_families_test.cpp).
TEST(TwoDriveProfile, ShippedDriveFamilyProfilesLoad) {
  const motion::DriveProfile iai = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/iai_pcon_two_axes.toml");
  ASSERT_TRUE(iai.axis_drives);
  const motion::DriveProfile& pcon = iai.axis_drives->y.drive;
  EXPECT_EQ(pcon.unit_id, 2);
  EXPECT_EQ(pcon.registers.status, 0x9005);
  EXPECT_EQ(pcon.registers.moving_status, 0x9007);  // MOVE in DSSE, apart from DSS1
  EXPECT_EQ(pcon.protocol.handshake, motion::CommandHandshake::kPulse);
  EXPECT_EQ(pcon.protocol.servo_on, 0x1000);
  EXPECT_EQ(pcon.alarm_meaning(0x083), "absolute move command before home return completed");
  const motion::DriveProfile oriental = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/oriental_az_two_axes.toml");
  ASSERT_TRUE(oriental.axis_drives);
  EXPECT_EQ(oriental.axis_drives->x.drive.registers.target_x, 0x1802);
  EXPECT_EQ(oriental.axis_drives->x.drive.registers.moving_status, -1);
  EXPECT_EQ(oriental.axis_drives->x.drive.alarm_meaning(0x4A), "return-to-home incomplete");
}

TEST(TwoDriveProfile, AMovingBitInASecondStatusRegisterMayReuseABitNumber) {
  // MOVE is bit 5 of DSSE; bit 5 of DSS1 is another signal. Without
  // moving_status the same bit number twice is refused.
  const std::string apart = error_of("alarm = 0x203\n", "alarm = 0x203\nmoving_status = 0x204\n");
  EXPECT_EQ(apart, "accepted");
  EXPECT_EQ(error_of("moving = 5\n", "moving = 3\n"),
            "two.toml: x.status_bits.in_position = 3: bit 3 is also x.status_bits.moving; expected "
            "a bit that no other status uses");
}

TEST(TwoDriveProfile, ErrorsNameTheDrivesTable) {
  EXPECT_EQ(error_of("actual = 0x200", "actual = 0x101"),
            "two.toml: x.registers.actual = 257: registers 257..258 overlap x.registers.target "
            "(256..257); expected registers that no other field of the same table uses");
  EXPECT_EQ(error_of("in_position = 2", "in_position = 1"),
            "two.toml: y.status_bits.in_position = 1: bit 1 is also y.status_bits.moving; "
            "expected a bit that no other status uses");
  EXPECT_EQ(error_of("speed_units_per_mm_s = 10 ", "speed_units_per_mm_s = 1000 "),
            "two.toml: motion.max_speed_mm_s = 200: it does not fit in one 16-bit speed register "
            "of the y axis drive; expected a speed of at most 65535 speed units (65.535 mm/s)");
  EXPECT_EQ(error_of("[y.link]\nunit_id = 2", "[y.link]\nunit_id = 2\nslave = 3"),
            "two.toml: y.link.slave = 3: unknown key (misspelt?); expected one of unit_id, "
            "word_order, response_timeout_ms, reconnect_timeout_ms");
  EXPECT_NE(error_of("[x]\n", "[x]\nurl = \"tcp://h:1\"\n")
                .find("two.toml: x.url = \"tcp://h:1\": bench URL tcp://h:1: expected"),
            std::string::npos);
  // A controller's table at the top of a two-drive file.
  EXPECT_NE(
      error_of("[motion]", "[registers]\ntarget_x = 0\n\n[motion]").find("two.toml: registers"),
      std::string::npos);
  // A bench of two drives without its Y drive.
  std::ifstream in(profile_path());
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  text.erase(text.find("[y]\n"), text.find("[motion]") - text.find("[y]\n"));
  try {
    motion::parse_drive_profile(text, "two.toml");
    FAIL() << "a bench of two drives without [y] was accepted";
  } catch (const motion::ProfileError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("two.toml: y: missing", 0), 0u) << e.what();
  }
}

}  // namespace
