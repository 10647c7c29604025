// Drive profiles: the shipped files load; a missing, unknown or inconsistent
// field is refused with an error naming it; 32-bit words in both orders.
#include "motion/drive_profile.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "config/error.hpp"
#include "motion/errors.hpp"

namespace {

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string kSim = std::string(RIG_SOURCE_DIR) + "/config/benches/sim.toml";

// The shipped sim profile with one line replaced (regex on the whole line).
std::string sim_with(const std::string& line_regex, const std::string& replacement) {
  const std::string text = read(kSim);
  std::string out = std::regex_replace(text, std::regex(line_regex), replacement);
  EXPECT_NE(out, text) << "pattern " << line_regex << " matched nothing";
  return out;
}

std::string error_of(const std::string& text) {
  try {
    motion::parse_drive_profile(text, "p.toml");
  } catch (const motion::ProfileError& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(DriveProfile, ShippedSimProfileIsTheDesignMap) {
  const motion::DriveProfile p = motion::load_drive_profile(kSim);
  EXPECT_EQ(p.word_order, motion::WordOrder::kHighFirst);
  EXPECT_EQ(p.counts_per_mm, 1000);
  EXPECT_EQ(p.registers.target_x, 0);
  EXPECT_EQ(p.registers.target_y, 2);
  EXPECT_EQ(p.registers.speed, 4);
  EXPECT_EQ(p.registers.command, 5);
  EXPECT_EQ(p.registers.feedback, motion::RegisterTable::kInput);
  EXPECT_EQ(p.registers.status, 4);
  EXPECT_EQ(p.registers.alarm, 5);
  EXPECT_EQ(p.status_bits.emergency_stop, 4);
  EXPECT_EQ(p.commands.reset_alarm, 4);
  EXPECT_EQ(p.alarm_meaning(3), "not homed: home before moving");
  EXPECT_EQ(p.alarm_meaning(77), "unknown alarm code 77");
}

TEST(DriveProfile, ShippedTemplateForARealDriveLoads) {
  const motion::DriveProfile p = motion::load_drive_profile(
      std::string(RIG_SOURCE_DIR) + "/config/benches/template_real_drive.toml");
  EXPECT_EQ(p.word_order, motion::WordOrder::kHighFirst);
  EXPECT_EQ(p.registers.feedback, motion::RegisterTable::kHolding);
}

TEST(DriveProfile, MissingFieldIsRefusedByName) {
  EXPECT_EQ(error_of(sim_with("target_y = 2[^\n]*", "")),
            "p.toml: registers.target_y: missing; expected an integer in 0..65535");
}

TEST(DriveProfile, MissingTableIsRefusedByName) {
  const std::string text = read(kSim);
  const std::string cut =
      text.substr(0, text.find("\n[soft_limits]")) + text.substr(text.find("\n[alarms]"));
  EXPECT_EQ(error_of(cut), "p.toml: soft_limits: missing; expected a table [soft_limits]");
}

TEST(DriveProfile, MisspeltKeyIsRefusedByName) {
  EXPECT_EQ(error_of(sim_with("settle_time_ms = 20", "settle_time_ms = 20\nsettle_tme_ms = 5")),
            "p.toml: motion.settle_tme_ms = 5: unknown key (misspelt?); expected one of "
            "default_speed_mm_s, max_speed_mm_s, position_tolerance_mm, home_x_mm, home_y_mm, "
            "poll_interval_ms, settle_time_ms, settle_timeout_ms, home_timeout_ms");
}

TEST(DriveProfile, OverlappingRegistersAreRefused) {
  EXPECT_EQ(error_of(sim_with("target_y = 2", "target_y = 1")),
            "p.toml: registers.target_y = 1: registers 1..2 overlap registers.target_x (0..1); "
            "expected registers that no other field of the same table uses");
}

TEST(DriveProfile, FeedbackInHoldingMustNotOverlapWrites) {
  EXPECT_EQ(error_of(sim_with("feedback = \"input\"", "feedback = \"holding\"")),
            "p.toml: registers.actual_x = 0: registers 0..1 overlap registers.target_x (0..1); "
            "expected registers that no other field of the same table uses");
}

TEST(DriveProfile, DuplicateStatusBitIsRefused) {
  EXPECT_EQ(error_of(sim_with("in_position = 2", "in_position = 1")),
            "p.toml: status_bits.in_position = 1: bit 1 is also status_bits.moving; expected a "
            "bit that no other status uses");
}

TEST(DriveProfile, DuplicateCommandCodeIsRefused) {
  EXPECT_EQ(error_of(sim_with("stop = 3", "stop = 2")),
            "p.toml: commands.stop = 2: code 2 is also commands.home; expected a code that no "
            "other command uses");
}

TEST(DriveProfile, UnknownWordOrderIsRefused) {
  EXPECT_EQ(error_of(sim_with("word_order = \"high_first\"", "word_order = \"big\"")),
            "p.toml: link.word_order = \"big\": expected \"high_first\" or \"low_first\"");
}

TEST(DriveProfile, EmptySoftLimitsAreRefused) {
  EXPECT_EQ(error_of(sim_with("x_max_mm = 900", "x_max_mm = -1")),
            "p.toml: soft_limits.x_max_mm = -1: expected a limit > soft_limits.x_min_mm (0)");
}

TEST(DriveProfile, ToleranceFinerThanOneCountIsRefused) {
  EXPECT_EQ(error_of(sim_with("position_tolerance_mm = 0.002", "position_tolerance_mm = 0.0001")),
            "p.toml: motion.position_tolerance_mm = 0.0001: finer than one count, the bench "
            "could never settle; expected a tolerance of at least one count (0.001 mm)");
}

TEST(DriveProfile, IntegerFieldGivenAsFloatIsRefused) {
  EXPECT_EQ(error_of(sim_with("unit_id = 1[^\n]*", "unit_id = 1.5")),
            "p.toml: link.unit_id = 1.5: expected an integer in 0..255");
}

TEST(DriveProfile, AlarmCodesAreReadInHexOrDecimal) {
  // Drive manuals often list alarm codes in hex: 0xB1 and 177 are the same code.
  const motion::DriveProfile p = motion::parse_drive_profile(
      sim_with("4 = \"bad command[^\n]*", "0xB1 = \"overload\"\n0x0A = \"ten\""), "p.toml");
  EXPECT_EQ(p.alarm_meaning(177), "overload");
  EXPECT_EQ(p.alarm_meaning(10), "ten");
  EXPECT_EQ(p.alarm_meaning(3), "not homed: home before moving");
  EXPECT_EQ(p.alarm_meaning(4), "unknown alarm code 4");
}

TEST(DriveProfile, AnAlarmCodeWrittenTwiceIsRefusedNamingBoth) {
  EXPECT_EQ(error_of(sim_with("4 = \"bad command[^\n]*", "0x2 = \"again\"")),
            "p.toml: alarms.2 = \"following error\": code 2 is also written as alarms.0x2; "
            "expected each code once");
}

TEST(DriveProfile, AnAlarmKeyThatIsNotACodeIsRefused) {
  EXPECT_EQ(error_of(sim_with("4 = \"bad command[^\n]*", "overload = \"x\"")),
            "p.toml: alarms.overload = \"x\": expected an alarm code in 1..65535 as the key, in "
            "decimal (177) or hex (0xB1)");
}

TEST(DriveProfile, MisspeltTableIsRefusedAndTheSimTableIsLeftToTheSimulatedBench) {
  const std::string text = read(kSim);
  EXPECT_NO_THROW(motion::parse_drive_profile(text, "p.toml"));  // has [sim]
  EXPECT_EQ(error_of(text + "\n[simm]\nseed = 1\n"),
            "p.toml: simm = { seed = 1 }: unknown key (misspelt?); expected one of name, link, "
            "units, registers, status_bits, commands, motion, soft_limits, handshake, alarms, sim");
}

TEST(DriveProfile, AProfileThatIsAFolderIsRefusedAsABadConfigurationFile) {
  try {
    motion::load_drive_profile(RIG_SOURCE_DIR "/config/benches");
    ADD_FAILURE() << "a folder loaded";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(dynamic_cast<const motion::ProfileError*>(&e), nullptr);
    EXPECT_EQ(std::string(e.what()), RIG_SOURCE_DIR
              "/config/benches: is a folder; expected the drive profile, a regular file");
  }
}

TEST(DriveProfile, WordOrdersRoundTripNegativeValues) {
  std::uint16_t w[2];
  motion::encode_int32(-2, motion::WordOrder::kHighFirst, w);
  EXPECT_EQ(w[0], 0xFFFF);
  EXPECT_EQ(w[1], 0xFFFE);
  EXPECT_EQ(motion::decode_int32(w, motion::WordOrder::kHighFirst), -2);
  motion::encode_int32(0x12345678, motion::WordOrder::kLowFirst, w);
  EXPECT_EQ(w[0], 0x5678);
  EXPECT_EQ(w[1], 0x1234);
  EXPECT_EQ(motion::decode_int32(w, motion::WordOrder::kLowFirst), 0x12345678);
}

const std::string kHandshake = std::string(RIG_SOURCE_DIR) + "/tests/motion/handshake_drive.toml";

// The handshake emulator's profile with one line replaced.
std::string handshake_with(const std::string& line_regex, const std::string& replacement) {
  const std::string text = read(kHandshake);
  std::string out = std::regex_replace(text, std::regex(line_regex), replacement);
  EXPECT_NE(out, text) << "pattern " << line_regex << " matched nothing";
  return out;
}

TEST(DriveProfile, HandshakeTableAndHexIntegersAreRead) {
  const motion::DriveProfile p = motion::load_drive_profile(kHandshake);
  EXPECT_EQ(p.registers.command, 0x105);  // written 0x105 in the file
  EXPECT_EQ(p.commands.reset_alarm, 8);   // 0x08
  EXPECT_EQ(p.protocol.handshake, motion::CommandHandshake::kSelfClearing);
  EXPECT_EQ(p.protocol.servo_on, 0x10);
  EXPECT_EQ(p.protocol.servo_ready_bit, 7);
  EXPECT_FALSE(p.protocol.reset_pulse);
  EXPECT_EQ(p.alarm_meaning(177), "servo off: command while the servo was not ready");
  // Without [handshake], rig's own convention: the register keeps the code.
  const motion::DriveProfile sim = motion::load_drive_profile(kSim);
  EXPECT_EQ(sim.protocol.handshake, motion::CommandHandshake::kKept);
  EXPECT_EQ(sim.protocol.servo_on, 0);
  EXPECT_EQ(sim.position_bits, 32);
}

TEST(DriveProfile, InconsistentHandshakesAreRefusedByName) {
  EXPECT_EQ(error_of(handshake_with("servo_ready_bit = 7[^\n]*", "")),
            "p.toml: handshake.servo_ready_bit: missing; expected the status bit (0..15) the "
            "drive sets once the servo is on, with handshake.servo_on");
  EXPECT_EQ(error_of(handshake_with("servo_ready_bit = 7", "servo_ready_bit = 5")),
            "p.toml: handshake.servo_ready_bit = 5: bit 5 is also status_bits.moving; expected a "
            "bit that no other status uses");
  EXPECT_EQ(error_of(handshake_with("home = 0x02", "home = 0x12")),
            "p.toml: commands.home = 18: the servo-on bits are kept set in every command; "
            "expected a code sharing no bit with handshake.servo_on (16)");
  EXPECT_EQ(error_of(handshake_with("stop = 0x04", "stop = 0")),
            "p.toml: commands.stop = 0: 0 is the cleared command register of handshake.command "
            "= \"self_clearing\"; expected a code other than 0");
  EXPECT_EQ(error_of(handshake_with("command = \"self_clearing\"", "command = \"toggle\"")),
            "p.toml: handshake.command = \"toggle\": expected \"kept\", \"self_clearing\" or "
            "\"pulse\"");
  EXPECT_EQ(
      error_of(handshake_with("command = \"self_clearing\"", "command = \"kept\"\nack_bit = 6")),
      "p.toml: handshake.ack_bit = 6: expected an ack_bit only with handshake.command = "
      "\"pulse\"");
}

TEST(DriveProfile, SixteenBitPositionsTakeOneRegisterAndBoundTheSoftLimits) {
  // One signed register at 100 counts/mm holds +-327.67 mm.
  const std::string one_register = handshake_with("position_bits = 32", "position_bits = 16");
  const motion::DriveProfile p = motion::parse_drive_profile(
      std::regex_replace(one_register, std::regex("target_y = 0x102"), "target_y = 0x101"),
      "p.toml");
  EXPECT_EQ(p.position_registers(), 1);
  std::uint16_t w[2] = {0, 0};
  p.encode_position(-1234, w);
  EXPECT_EQ(w[0], 0x10000 - 1234);
  EXPECT_EQ(p.decode_position(w), -1234);
  EXPECT_EQ(
      error_of(std::regex_replace(one_register, std::regex("x_max_mm = 200"), "x_max_mm = 400")),
      "p.toml: soft_limits.x_max_mm = 400: expected a limit that fits in a signed 16-bit "
      "position register (|limit| <= 327.66 mm at units.counts_per_mm = 100)");
  EXPECT_EQ(error_of(handshake_with("position_bits = 32", "position_bits = 24")),
            "p.toml: units.position_bits = 24: expected 16 or 32");
}

}  // namespace
