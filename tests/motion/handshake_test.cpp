// Command conventions of third-party drives as profile data ([handshake],
// units.position_bits; docs/drive-profile.md): the real driver against a real
// Modbus TCP server, tests/motion/handshake_drive.py (pymodbus), that behaves
// each way: a control word the drive clears itself, edge-triggered bits with
// an acknowledge, a servo-on that must stay set, 16-bit positions.
//
// Positions are exact: the emulator moves in whole counts (0.01 mm) and stops
// on the target count, and the driver quantizes a target to the same counts,
// so a settled read-back equals the target to within rounding of the mm <->
// counts conversion (1e-9 mm).
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "child_process.hpp"
#include "drive_emulator.hpp"
#include "motion/drive_profile.hpp"
#include "motion/errors.hpp"
#include "motion/modbus_bench.hpp"

namespace {

using namespace std::chrono_literals;
using motion_test::kEmulatorStart;
using motion_test::kExact;
using motion_test::kSettle;
using rig_test::ChildProcess;

// The emulator's control and status registers (handshake_drive.py).
constexpr int kControl = 0x105;
constexpr std::uint16_t kSon = 0x10;

class HandshakeDrive : public ::testing::Test {
 protected:
  // Starts the emulator with `args` (e.g. {"--control", "clears", "--servo"}).
  void start(const std::vector<std::string>& args) {
    std::vector<std::string> argv = {
        "/usr/bin/python3", std::string(RIG_SOURCE_DIR) + "/tests/motion/handshake_drive.py", "0"};
    argv.insert(argv.end(), args.begin(), args.end());
    drive_ = std::make_unique<ChildProcess>(argv);
    const auto line = drive_->read_line(kEmulatorStart);
    ASSERT_TRUE(line && line->rfind("PORT ", 0) == 0)
        << "handshake emulator did not start (python3-pymodbus installed?)";
    port_ = std::stoi(line->substr(5));
  }
  std::unique_ptr<motion::ModbusBench> connect() {
    motion::validate(profile_);
    return std::make_unique<motion::ModbusBench>(
        motion::BenchUrl::parse("modbus-tcp://127.0.0.1:" + std::to_string(port_)), profile_);
  }
  // Reads `n` holding registers from `address` with libmodbus directly.
  std::vector<std::uint16_t> raw(int address, int n) {
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port_);
    std::vector<std::uint16_t> regs(n);
    EXPECT_EQ(modbus_connect(ctx), 0);
    EXPECT_EQ(modbus_read_registers(ctx, address, n, regs.data()), n);
    modbus_close(ctx);
    modbus_free(ctx);
    return regs;
  }
  void no_servo() {
    profile_.protocol.servo_on = 0;
    profile_.protocol.servo_ready_bit = -1;
  }
  void pulse(int ack_bit) {
    profile_.protocol.handshake = motion::CommandHandshake::kPulse;
    profile_.protocol.ack_bit = ack_bit;
  }
  static void expect_at(const motion::BenchStatus& s, double x, double y) {
    EXPECT_NEAR(s.position.x_mm, x, kExact);
    EXPECT_NEAR(s.position.y_mm, y, kExact);
    EXPECT_TRUE(s.in_position);
  }

  std::unique_ptr<ChildProcess> drive_;
  int port_ = 0;
  motion::DriveProfile profile_ = motion::load_drive_profile(std::string(RIG_SOURCE_DIR) +
                                                             "/tests/motion/handshake_drive.toml");
};

TEST_F(HandshakeDrive, SelfClearingControlWordFailsTheReadBackOfAKeptProfile) {
  // The drive clears HOME (2) at once and keeps SON (16): a profile that
  // expects the register to keep its code sees 16 where it wrote 18.
  start({"--control", "clears", "--servo"});
  profile_.protocol.handshake = motion::CommandHandshake::kKept;
  auto bench = connect();
  try {
    bench->home();
    FAIL() << "a self-clearing register passed the read-back of a kept profile";
  } catch (const motion::BenchWriteError& e) {
    EXPECT_NE(std::string(e.what()).find("home: holding registers 261..261 read back [16] after "
                                         "writing [18]"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(HandshakeDrive, SelfClearingControlWordWithServoOnIsDriven) {
  start({"--control", "clears", "--servo"});
  auto bench = connect();
  bench->home();
  expect_at(bench->wait_settled(kSettle), 0, 0);
  bench->move_to(-12.34, 56.78);
  expect_at(bench->wait_settled(kSettle), -12.34, 56.78);
  bench->move_to(30, 20);  // a second start of the same bit: the drive cleared the first
  expect_at(bench->wait_settled(kSettle), 30, 20);
  // The drive cleared the command bits; the servo-on bit stayed set.
  EXPECT_EQ(raw(kControl, 1)[0], kSon);
}

TEST_F(HandshakeDrive, WithoutTheServoOnTheDrivesAlarmIsReported) {
  start({"--control", "clears", "--servo"});
  no_servo();
  auto bench = connect();
  bench->home();
  try {
    bench->wait_settled(kSettle);
    FAIL() << "homed without the servo on";
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), 0xB1);
    EXPECT_EQ(e.meaning(), "servo off: command while the servo was not ready");
  }
}

TEST_F(HandshakeDrive, SelfClearingCommandTheDriveIgnoresTimesOutClearly) {
  // The drive refuses HOME with the servo off; with its alarm bit not in the
  // profile (status_bits.alarm moved to an unused bit) nothing in the status
  // shows the command was taken, and the driver says so after the timeout.
  start({"--control", "clears", "--servo"});
  no_servo();
  profile_.status_bits.alarm = 14;
  profile_.protocol.accept_timeout_ms = 300;
  auto bench = connect();
  try {
    bench->home();
    FAIL() << "a command the drive did not take was reported sent";
  } catch (const motion::BenchWriteError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "home: the drive did not take command 2 within handshake.accept_timeout_ms = "
                  "300 ms"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(HandshakeDrive, EdgeTriggeredStartWithAcknowledgeIsSetAndCleared) {
  start({"--control", "edge"});
  no_servo();
  pulse(6);  // ACK
  auto bench = connect();
  bench->home();
  expect_at(bench->wait_settled(kSettle), 0, 0);
  bench->move_to(10, 5);
  expect_at(bench->wait_settled(kSettle), 10, 5);
  bench->move_to(-20.5, 7.25);  // needs a new rising edge of CSTR
  expect_at(bench->wait_settled(kSettle), -20.5, 7.25);
  EXPECT_EQ(raw(kControl, 1)[0], 0);  // cleared after the acknowledge
}

TEST_F(HandshakeDrive, EdgeTriggeredStartHeldForAStatedTimeWithoutAcknowledge) {
  start({"--control", "edge", "--servo"});
  pulse(-1);
  profile_.protocol.pulse_ms = 20;
  auto bench = connect();
  bench->home();
  expect_at(bench->wait_settled(kSettle), 0, 0);
  bench->move_to(10, 5);
  expect_at(bench->wait_settled(kSettle), 10, 5);
  bench->move_to(11, 6);
  expect_at(bench->wait_settled(kSettle), 11, 6);
  EXPECT_EQ(raw(kControl, 1)[0], kSon);
}

TEST_F(HandshakeDrive, EdgeTriggeredDriveIgnoresAStartBitThatStaysSet) {
  // The convention matters: kept, the second move writes CSTR over CSTR, no
  // edge, and the drive stays where it was. 0.5 s is 4x the 0.12 s the 25 mm
  // move takes at 200 mm/s, so a drive that took it would have settled.
  start({"--control", "edge"});
  no_servo();
  profile_.protocol.handshake = motion::CommandHandshake::kKept;
  auto bench = connect();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(10, 5);
  expect_at(bench->wait_settled(kSettle), 10, 5);
  bench->move_to(35, 5);
  EXPECT_THROW(bench->wait_settled(500ms), motion::BenchTimeout);
  EXPECT_NEAR(bench->position().x_mm, 10, kExact);
}

TEST_F(HandshakeDrive, AlarmResetAsAPulseClearsRepeatedAlarms) {
  // The edge drive resets on the rising edge of RES only: the pulse clears
  // RES after each reset, so a second alarm is reset as well.
  start({"--control", "edge"});
  no_servo();
  profile_.protocol.handshake = motion::CommandHandshake::kKept;
  profile_.protocol.reset_pulse = true;
  profile_.protocol.pulse_ms = 20;
  auto bench = connect();
  for (int i = 0; i < 2; ++i) {
    bench->move_to(1, 1);  // not homed: alarm 4
    EXPECT_THROW(bench->wait_settled(kSettle), motion::BenchFault);
    bench->reset_alarm();  // throws if the alarm persists
    EXPECT_FALSE(bench->status().alarm);
    EXPECT_EQ(raw(kControl, 1)[0], 0);
  }
}

TEST_F(HandshakeDrive, SixteenBitPositionsAreOneSignedRegisterEach) {
  start({"--control", "clears", "--servo", "--position-bits", "16"});
  profile_.position_bits = 16;
  profile_.registers.target_y = 0x101;
  profile_.registers.actual_y = 0x201;
  auto bench = connect();
  bench->home();
  bench->wait_settled(kSettle);
  bench->move_to(-12.34, 56.78);
  expect_at(bench->wait_settled(kSettle), -12.34, 56.78);
  const std::vector<std::uint16_t> targets = raw(0x100, 2);
  EXPECT_EQ(targets[0], 0x10000 - 1234);  // -12.34 mm in 0.01 mm, two's complement
  EXPECT_EQ(targets[1], 5678);
}

}  // namespace
