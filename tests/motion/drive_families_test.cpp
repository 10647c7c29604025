// The shipped drive-family profiles (config/benches/iai_pcon_two_axes.toml,
// config/benches/oriental_az_two_axes.toml) driven by the real driver
// (TwoDriveBench) against tests/motion/drive_families.py, which emulates two
// drives of each family, X at unit 1 and Y at unit 2 on one Modbus line, the
// way the profile's header says the manual describes them: the PCON's
// edge-triggered DRG1 with a servo-on kept set, PEND dropping on the start
// and rising after the move with CSTR released, HEND after homing, MOVE in
// DSSE; the AZ's remote inputs acting on rising edges, IN-POS and HOME-END;
// each family's alarm codes and alarm reset. Over Modbus TCP, and the AZ pair
// also over Modbus RTU through a socat pty pair.
//
// Positions are exact: the emulator moves in whole counts (0.01 mm, or one
// step = 0.01 mm) and stops on the target count, and the driver quantizes a
// target to the same counts, so a settled read-back equals the target to
// within the rounding of the mm <-> counts conversion (1e-9 mm).
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <signal.h>

#include <chrono>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "drive_emulator.hpp"
#include "motion/drive_profile.hpp"
#include "motion/errors.hpp"
#include "motion/two_drive_bench.hpp"
#include "pty_pair.hpp"

namespace {

using namespace std::chrono_literals;
using motion_test::kEmulatorStart;
using motion_test::kExact;
using motion_test::kSettle;
using rig_test::ChildProcess;

// What the test needs of one family: its profile, its map and its alarms.
struct Family {
  std::string name;     // drive_families.py --family
  std::string profile;  // under config/benches
  int target;           // first target register (upper word)
  int actual;           // first read-back register (upper word)
  int command;          // command register
  int speed;            // speed register (lower word)
  std::uint16_t held;   // bits the command register keeps after a command (servo-on)
  int not_homed;        // alarm of a move before homing
  std::string not_homed_meaning;
  int overload;  // alarm the emulator raises on SIGUSR1
};

const Family kPcon{"pcon",
                   "iai_pcon_two_axes.toml",
                   0x1000,
                   0x9000,
                   0x0D00,
                   0x1005,
                   0x1000,
                   0x083,
                   "absolute move command before home return completed",
                   0x0E0};
const Family kAz{"az", "oriental_az_two_axes.toml", 0x1802, 0x00CC, 0x007D, 0x1805, 0,
                 0x4A, "return-to-home incomplete", 0x30};

// ctest lists a case by its family's name.
void PrintTo(const Family& f, std::ostream* os) {
  *os << f.name;
}

class DriveFamily : public ::testing::TestWithParam<Family> {
 protected:
  const Family& family() const { return GetParam(); }
  // Starts the emulator of the family with `args`, over TCP.
  void start(const std::vector<std::string>& args = {}) {
    std::vector<std::string> argv = {
        "/usr/bin/python3", std::string(RIG_SOURCE_DIR) + "/tests/motion/drive_families.py",
        "--family", family().name};
    argv.insert(argv.end(), args.begin(), args.end());
    drives_ = std::make_unique<ChildProcess>(argv);
    const auto line = drives_->read_line(kEmulatorStart);
    ASSERT_TRUE(line && line->rfind("PORT ", 0) == 0)
        << "drive-family emulator did not start (python3-pymodbus installed?)";
    port_ = std::stoi(line->substr(5));
  }
  std::string url() const { return "modbus-tcp://127.0.0.1:" + std::to_string(port_); }
  std::unique_ptr<motion::TwoDriveBench> connect() {
    return std::make_unique<motion::TwoDriveBench>(motion::BenchUrl::parse(url()), profile_);
  }
  // `n` holding registers at `address` of `unit`, read with libmodbus directly.
  std::vector<std::uint16_t> raw(int unit, int address, int n) const {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port_);
    modbus_set_slave(ctx, unit);
    std::vector<std::uint16_t> regs(n);
    EXPECT_EQ(modbus_connect(ctx), 0);
    EXPECT_EQ(modbus_read_registers(ctx, address, n, regs.data()), n);
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
  // Both units' registers: upper word first, counts of 0.01 mm.
  static std::vector<std::uint16_t> counts(std::int32_t c) {
    const auto u = static_cast<std::uint32_t>(c);
    return {static_cast<std::uint16_t>(u >> 16), static_cast<std::uint16_t>(u & 0xFFFF)};
  }

  std::unique_ptr<ChildProcess> drives_;
  int port_ = 0;
  motion::DriveProfile profile_ = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/" + GetParam().profile);
};

TEST_P(DriveFamily, HomesMovesBothAxesSettlesAndReadsBackInTheFamilysUnits) {
  start();
  auto bench = connect();
  // Connecting writes nothing: a PCON's servo stays off until the first command.
  EXPECT_EQ(raw(1, family().command, 1)[0], 0);
  EXPECT_FALSE(bench->status().homed);
  bench->home();
  const motion::BenchStatus home = bench->wait_settled(kSettle);
  expect_at(home, 0, 0);
  EXPECT_TRUE(home.homed);
  bench->set_speed(100);
  bench->move_to(12.34, 56.78);
  expect_at(bench->wait_settled(kSettle), 12.34, 56.78);

  // Each drive holds its axis in 0.01 mm counts, upper word first, the
  // speed in 0.01 mm/s; the command register holds only the servo-on (PCON
  // SON) once the start pulse is over.
  for (const auto& [unit, c] : {std::pair<int, std::int32_t>{1, 1234}, {2, 5678}}) {
    EXPECT_EQ(raw(unit, family().target, 2), counts(c)) << "unit " << unit;
    EXPECT_EQ(raw(unit, family().actual, 2), counts(c)) << "unit " << unit;
    EXPECT_EQ(raw(unit, family().speed, 1)[0], 10000) << "unit " << unit;
    EXPECT_EQ(raw(unit, family().command, 1)[0], family().held) << "unit " << unit;
  }
  EXPECT_EQ(bench->reconnects(), 0);
}

TEST_P(DriveFamily, StopEndsTheMoveShortOfItsTargetAndItDoesNotResume) {
  start();
  auto bench = connect();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(100, 100);  // 2 s at the profile's 50 mm/s
  bench->stop();
  const motion::BenchStatus stopped = bench->status();
  EXPECT_FALSE(stopped.moving);
  EXPECT_FALSE(stopped.in_position);  // positioning was not completed
  EXPECT_LT(stopped.position.x_mm, 100);
  EXPECT_LT(stopped.position.y_mm, 100);
  // The PCON pauses on STP and resumes when STP drops unless ALRS cancelled
  // the rest of the travel; the AZ's STOP cancels the operation. A move
  // that resumed would cover 250 counts (2.5 mm at 50 mm/s) in 50 ms: the
  // position must not change by one.
  std::this_thread::sleep_for(50ms);
  const motion::BenchStatus later = bench->status();
  EXPECT_FALSE(later.moving);
  EXPECT_EQ(later.position.x_mm, stopped.position.x_mm);
  EXPECT_EQ(later.position.y_mm, stopped.position.y_mm);
  // A new move after the stop goes.
  bench->set_speed(100);
  bench->move_to(20, 30);
  expect_at(bench->wait_settled(kSettle), 20, 30);
}

TEST_P(DriveFamily, AMoveBeforeHomingRaisesTheFamilysAlarmWhichResets) {
  start();
  auto bench = connect();
  bench->move_to(10, 10);
  try {
    bench->wait_settled(kSettle);
    FAIL() << "a move before homing was not refused";
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), family().not_homed);
    EXPECT_EQ(e.meaning(), family().not_homed_meaning);
    const std::string what = e.what();
    EXPECT_NE(
        what.find(url() + "?unit=1 (X axis drive): alarm " + std::to_string(family().not_homed) +
                  " (" + family().not_homed_meaning + ") at 5 mm"),
        std::string::npos)
        << what;
  }
  // Neither drive moved from where it powered up.
  const motion::BenchStatus s = bench->status();
  EXPECT_TRUE(s.alarm);
  EXPECT_EQ(s.position.x_mm, 5);
  EXPECT_EQ(s.position.y_mm, 5);
  bench->reset_alarm();
  EXPECT_FALSE(bench->status().alarm);
  EXPECT_EQ(raw(1, family().command, 1)[0], family().held);  // the reset pulse is over
  bench->home();
  bench->wait_settled(kSettle);
  bench->set_speed(100);
  bench->move_to(10, 10);
  expect_at(bench->wait_settled(kSettle), 10, 10);
}

TEST_P(DriveFamily, AnAlarmOnTheYDriveDuringAMoveStopsXAndIsReset) {
  start();
  auto bench = connect();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(100, 100);  // 2 s at 50 mm/s
  drives_->signal(SIGUSR1);  // the Y drive's overload alarm
  try {
    bench->wait_settled(kSettle);
    FAIL() << "the Y drive's overload went unreported";
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), family().overload);
    EXPECT_EQ(e.meaning(), "overload");
    EXPECT_NE(std::string(e.what()).find("?unit=2 (Y axis drive): alarm " +
                                         std::to_string(family().overload) + " (overload)"),
              std::string::npos)
        << e.what();
  }
  const motion::BenchStatus x = bench->x_drive().status();
  EXPECT_FALSE(x.moving);
  EXPECT_FALSE(x.alarm);
  EXPECT_LT(x.position.x_mm, 100);
  EXPECT_EQ(bench->status().alarm_meaning, "Y axis: overload");
  bench->reset_alarm();
  EXPECT_FALSE(bench->status().alarm);
  bench->set_speed(100);
  bench->move_to(30, 40);
  expect_at(bench->wait_settled(kSettle), 30, 40);
}

TEST_P(DriveFamily, ATargetTheYDriveRefusesStartsNeitherDrive) {
  start({"--refuse-target-writes", "2"});
  auto bench = connect();
  bench->home();
  bench->wait_settled(kSettle);
  try {
    bench->move_to(100, 50);
    FAIL() << "the Y drive's refusal went unreported";
  } catch (const motion::BenchWriteError& e) {
    const std::string what = e.what();
    const std::string y = url() + "?unit=2 (Y axis drive)";
    EXPECT_NE(
        what.find(y + ": move_to (targets): the drive refused holding registers " +
                  std::to_string(family().target) + ".." + std::to_string(family().target + 1)),
        std::string::npos)
        << what;
    EXPECT_NE(what.find("neither drive was started: bench " + url() +
                        "?unit=1 (X axis drive) stands at 0 mm, its target registers hold 100 "
                        "mm (its new target); bench " +
                        y + " stands at 0 mm, its target registers hold 0 mm"),
              std::string::npos)
        << what;
  }
  // X was written and not started: a start would have it moving, or past 0
  // mm, by the time its 50 ms start pulse ended.
  const motion::BenchStatus s = bench->status();
  EXPECT_FALSE(s.moving);
  EXPECT_EQ(s.position.x_mm, 0);
  EXPECT_EQ(s.position.y_mm, 0);
  EXPECT_FALSE(s.alarm);
}

INSTANTIATE_TEST_SUITE_P(Families, DriveFamily, ::testing::Values(kPcon, kAz),
                         [](const ::testing::TestParamInfo<Family>& info) {
                           return info.param.name;
                         });

// The PCON's servo-on, taken out of the profile: the controllers then refuse
// a home return with their alarm 080h, so the profile's servo_on is what
// makes them move.
class PconDrives : public DriveFamily {};

TEST_P(PconDrives, WithoutTheServoOnAHomeReturnIsRefusedWithAlarm080h) {
  start();
  auto drives = std::make_shared<motion::AxisDrives>(*profile_.axis_drives);
  for (motion::AxisDrive* d : {&drives->x, &drives->y}) {
    d->drive.protocol.servo_on = 0;
    d->drive.protocol.servo_ready_bit = -1;
  }
  profile_.axis_drives = drives;
  auto bench = connect();
  bench->home();
  try {
    bench->wait_settled(kSettle);
    FAIL() << "a home return with the servo off was not refused";
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), 0x080);
    EXPECT_EQ(e.meaning(), "move command while the servo is off");
  }
  EXPECT_EQ(bench->status().position.x_mm, 5);  // where it powered up
}

INSTANTIATE_TEST_SUITE_P(Families, PconDrives, ::testing::Values(kPcon),
                         [](const ::testing::TestParamInfo<Family>& info) {
                           return info.param.name;
                         });

// The AZ pair over Modbus RTU: the emulator serves one end of a socat pty
// pair, the driver opens the other at 115200 baud 8E1 (the profile header's
// link) as the URL says. Ptys carry bytes whatever their settings (and
// pyserial cannot set parity on one, so the emulator's end is 8N1): this
// checks the RTU framing with two stations on one line, not serial timing.
TEST(DriveFamilyRtu, TheAzPairIsDrivenOverRtuThroughAPtyPair) {
  const rig_test::PtyPair serial;
  ChildProcess drives({"/usr/bin/python3",
                       std::string(RIG_SOURCE_DIR) + "/tests/motion/drive_families.py", "--family",
                       "az", "--rtu", serial.drive_end(), "--baud", "115200", "--parity", "N",
                       "--stop", "1"});
  const auto line = drives.read_line(kEmulatorStart);
  ASSERT_TRUE(line && *line == "READY") << "drive-family emulator did not start over RTU";
  const motion::DriveProfile profile = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/oriental_az_two_axes.toml");
  motion::TwoDriveBench bench(motion::BenchUrl::parse("modbus-rtu://" + serial.driver_end() +
                                                      "?baud=115200&parity=E&stop=1"),
                              profile);
  bench.home();
  const motion::BenchStatus home = bench.wait_settled(kSettle);
  EXPECT_TRUE(home.homed);
  EXPECT_NEAR(home.position.x_mm, 0, kExact);
  EXPECT_NEAR(home.position.y_mm, 0, kExact);
  bench.set_speed(100);
  bench.move_to(23.45, 6.78);
  const motion::BenchStatus s = bench.wait_settled(kSettle);
  EXPECT_NEAR(s.position.x_mm, 23.45, kExact);
  EXPECT_NEAR(s.position.y_mm, 6.78, kExact);
  EXPECT_TRUE(s.in_position);
}

}  // namespace
