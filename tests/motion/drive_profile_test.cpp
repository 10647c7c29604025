// Drive profiles: the shipped files load; a missing, unknown or inconsistent
// field is refused with an error naming it; 32-bit words in both orders.
#include "motion/drive_profile.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>
#include <string>

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
            "p.toml: registers.target_y: missing (required)");
}

TEST(DriveProfile, MissingTableIsRefusedByName) {
  const std::string text = read(kSim);
  const std::string cut =
      text.substr(0, text.find("\n[soft_limits]")) + text.substr(text.find("\n[alarms]"));
  EXPECT_EQ(error_of(cut), "p.toml: soft_limits: missing table [soft_limits]");
}

TEST(DriveProfile, MisspeltKeyIsRefusedByName) {
  EXPECT_EQ(error_of(sim_with("settle_time_ms = 20", "settle_time_ms = 20\nsettle_tme_ms = 5")),
            "p.toml: motion.settle_tme_ms: unknown key (misspelt?)");
}

TEST(DriveProfile, OverlappingRegistersAreRefused) {
  EXPECT_EQ(error_of(sim_with("target_y = 2", "target_y = 1")),
            "p.toml: registers.target_y: registers 1..2 overlap registers.target_x (0..1)");
}

TEST(DriveProfile, FeedbackInHoldingMustNotOverlapWrites) {
  EXPECT_EQ(error_of(sim_with("feedback = \"input\"", "feedback = \"holding\"")),
            "p.toml: registers.actual_x: registers 0..1 overlap registers.target_x (0..1)");
}

TEST(DriveProfile, DuplicateStatusBitIsRefused) {
  EXPECT_EQ(error_of(sim_with("in_position = 2", "in_position = 1")),
            "p.toml: status_bits.in_position: bit 1 is also status_bits.moving");
}

TEST(DriveProfile, DuplicateCommandCodeIsRefused) {
  EXPECT_EQ(error_of(sim_with("stop = 3", "stop = 2")),
            "p.toml: commands.stop: code 2 is also commands.home");
}

TEST(DriveProfile, UnknownWordOrderIsRefused) {
  EXPECT_EQ(error_of(sim_with("word_order = \"high_first\"", "word_order = \"big\"")),
            "p.toml: link.word_order: \"big\" is not \"high_first\" or \"low_first\"");
}

TEST(DriveProfile, EmptySoftLimitsAreRefused) {
  EXPECT_EQ(error_of(sim_with("x_max_mm = 900", "x_max_mm = -1")),
            "p.toml: soft_limits.x_max_mm: must be > x_min_mm");
}

TEST(DriveProfile, ToleranceFinerThanOneCountIsRefused) {
  EXPECT_NE(error_of(sim_with("position_tolerance_mm = 0.002", "position_tolerance_mm = 0.0001"))
                .find("p.toml: motion.position_tolerance_mm: 0.000100 mm is finer than one count"),
            std::string::npos);
}

TEST(DriveProfile, IntegerFieldGivenAsFloatIsRefused) {
  EXPECT_EQ(error_of(sim_with("unit_id = 1[^\n]*", "unit_id = 1.5")),
            "p.toml: link.unit_id: expected an integer");
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

}  // namespace
