// motion::DriveProfile: everything ModbusBench knows about a drive, read from a
// TOML file (config/benches/*.toml), never from code. The default map of the
// simulated bench is docs/register-map.md and ships as config/benches/sim.toml; a documented
// template for a real drive is config/benches/template_real_drive.toml, for two
// single-axis drives config/benches/template_two_drives.toml.
//
// Registers are 0-based PDU addresses (Modbus "40001" = holding address 0).
// Positions are signed 32-bit two's complement counts in two consecutive
// registers, in the profile's word order (or, with units.position_bits = 16,
// signed 16-bit counts in one register); counts_per_mm converts them to mm.
// Every field is required except units.position_bits, the [handshake] table
// (command conventions, CommandProtocol) and the [alarms] table; a missing, unknown,
// mistyped or inconsistent field throws ProfileError naming it. [alarms] maps
// alarm codes to their meanings; a code is written in decimal (177 = "...")
// or in hex as drive manuals often list them (0xB1 = "..."), once.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "motion/bench_url.hpp"

namespace motion {

// Order of the two 16-bit words of a 32-bit value. kHighFirst: the register at
// the lower address holds bits 31..16 (rig's default map, Oriental Motor AZ);
// kLowFirst: it holds bits 15..0 (many IAI and PLC maps).
enum class WordOrder { kHighFirst, kLowFirst };

// Which table the drive's feedback (actual position, status, alarm) lives in:
// input registers (function 04) or holding registers (function 03). Many real
// drives expose everything as holding registers.
enum class RegisterTable { kInput, kHolding };

struct RegisterMap {
  // Holding registers written by the driver.
  int target_x = 0;  // first of 2 registers, int32 counts
  int target_y = 2;  // first of 2 registers, int32 counts
  int speed = 4;     // 1 register, unsigned, speed units (see DriveProfile)
  int command = 5;   // 1 register, command codes (see CommandCodes)
  // Feedback read by the driver, in `feedback`'s table.
  RegisterTable feedback = RegisterTable::kInput;
  int actual_x = 0;  // first of 2 registers, int32 counts
  int actual_y = 2;  // first of 2 registers, int32 counts
  int status = 4;    // 1 register of status bits (see StatusBits)
  int alarm = 5;     // 1 register, alarm code (0 = none)
  // Optional (-1: none): a second status register, in the feedback table,
  // holding the moving bit (status_bits.moving) when the drive keeps it apart
  // from the others (IAI: MOVE in DSSE 9007h, PEND and HEND in DSS1 9005h).
  int moving_status = -1;
};

// Bit positions (0..15) in the status register.
struct StatusBits {
  int homed = 0;
  int moving = 1;
  int in_position = 2;  // positioning complete (IAI "PEND")
  int alarm = 3;
  int emergency_stop = 4;
};

// Values written to the command register.
struct CommandCodes {
  std::uint16_t move_absolute = 1;
  std::uint16_t home = 2;
  std::uint16_t stop = 3;
  std::uint16_t reset_alarm = 4;
};

// The box the driver is allowed to command, mm. A move outside is refused
// before anything is sent (SoftLimitError). Keep it inside the drive's own
// travel limits so the drive's limit alarm is never the first line of defence.
struct SoftLimits {
  double x_min_mm = 0, x_max_mm = 0;
  double y_min_mm = 0, y_max_mm = 0;
  bool contains(double x_mm, double y_mm) const {
    return x_mm >= x_min_mm && x_mm <= x_max_mm && y_mm >= y_min_mm && y_mm <= y_max_mm;
  }
  // The SoftLimitError message for a move to (x_mm, y_mm) that these limits
  // refuse, naming the target, the box and `source` (the profile's file).
  std::string refusal(double x_mm, double y_mm, const std::string& source) const;
};

struct Timing {
  // Modbus response timeout. Shorter detects a dead link sooner; too short
  // turns a slow drive (RTU at low baud, busy gateway) into reconnect storms.
  int response_timeout_ms = 200;
  // How long the driver keeps trying to reconnect (with backoff) before it
  // raises BenchLinkError. Longer rides out a gateway reboot; shorter stops a
  // sweep sooner when a cable is really unplugged.
  int reconnect_timeout_ms = 3000;
  // Interval between status reads in wait_settled. Shorter notices settling
  // sooner at the cost of more bus traffic (matters on RTU).
  int poll_interval_ms = 5;
  // The bench must stay in position for this long before it counts as
  // settled. Longer lets mechanical ringing die out; it adds to every point.
  int settle_time_ms = 20;
  // Default wait_settled timeout for a move, and for homing.
  int settle_timeout_ms = 10000;
  int home_timeout_ms = 30000;
};

// How the drive takes a code written to the command register
// (docs/drive-profile.md#handshake-optional).
enum class CommandHandshake {
  // The register keeps the code written; the driver reads it back and compares.
  kKept,
  // The drive clears the register once it took the command; acceptance is seen
  // in the status instead (see ModbusBench), within accept_timeout_ms.
  kSelfClearing,
  // Edge-triggered: the code is set, held until the drive sets ack_bit (or
  // for pulse_ms when there is no ack_bit), then cleared.
  kPulse,
};

// The command conventions of a drive: handshake, servo-on before the first
// move, alarm reset as a pulse. The defaults describe rig's own map.
struct CommandProtocol {
  CommandHandshake handshake = CommandHandshake::kKept;
  // kSelfClearing, kPulse with ack_bit, and enable: how long the driver waits
  // for the drive to show it took a command, ms.
  int accept_timeout_ms = 1000;
  // kPulse: status bit the drive sets once it took the command; -1: none,
  // hold the code for pulse_ms instead.
  int ack_bit = -1;
  // How long a pulse (kPulse without ack_bit, reset_pulse) is held, ms.
  int pulse_ms = 50;
  // Bits written to the command register before the first home or move and
  // kept set (OR-ed) in every code written afterwards; 0: no servo-on.
  std::uint16_t servo_on = 0;
  // Status bit the drive sets when the servo is on; required with servo_on.
  int servo_ready_bit = -1;
  // The alarm reset is written, held pulse_ms and cleared (drives that reset
  // on a rising edge), whatever the handshake.
  bool reset_pulse = false;
};

struct AxisDrives;

struct DriveProfile {
  std::string name;    // free text, for logs
  std::string source;  // file it was read from (for messages)
  // 0: a controller of both axes (target_x/y, actual_x/y). 'x' or 'y': a
  // single-axis drive, one axis of a bench of two drives (AxisDrives): only
  // target_x, actual_x, the soft limits x_min_mm/x_max_mm and home_x_mm are
  // used, and they describe this drive's axis; messages name it ("Y axis
  // drive") and its fields ("y.registers.target").
  char axis = 0;
  // Set on the profile of a bench of two single-axis drives (a file with
  // [x] and [y] tables): the bench's own fields here (name, [motion],
  // [soft_limits]) are shared; the drives' are in *axis_drives. Null for a
  // single controller.
  std::shared_ptr<const AxisDrives> axis_drives;
  int unit_id = 1;  // Modbus unit (slave) id, 1..247, or 255 for TCP
  WordOrder word_order = WordOrder::kHighFirst;
  double counts_per_mm = 1000;  // position register units per mm (1000 = µm)
  // Width of a position register value: 32 (two registers, word_order) or 16
  // (one register, signed).
  int position_bits = 32;
  double speed_units_per_mm_s = 1;  // speed register units per mm/s
  double default_speed_mm_s = 50;   // written with every move
  double max_speed_mm_s = 100;      // set_speed refuses more
  // wait_settled requires |read-back - target| <= this on both axes, mm. At
  // least one count; tighter than the drive's in-position band never settles.
  double position_tolerance_mm = 0.005;
  double home_x_mm = 0, home_y_mm = 0;  // where the bench is after homing
  RegisterMap registers;
  StatusBits status_bits;
  CommandCodes commands;
  SoftLimits soft_limits;
  Timing timing;
  std::map<int, std::string> alarm_meanings;  // code -> meaning
  CommandProtocol protocol;

  bool single_axis() const { return axis != 0; }
  // Registers one position takes: 2 for 32-bit values, 1 for 16-bit ones.
  int position_registers() const { return position_bits == 16 ? 1 : 2; }
  // A position's counts as its registers (position_registers() of them);
  // precondition: the counts fit in position_bits.
  void encode_position(std::int32_t counts, std::uint16_t out[2]) const;
  std::int32_t decode_position(const std::uint16_t in[2]) const;

  // mm -> counts, rounded to nearest. Precondition: the result fits in int32
  // (guaranteed for values inside the validated soft limits).
  std::int32_t to_counts(double mm) const;
  double to_mm(std::int32_t counts) const { return counts / counts_per_mm; }
  // The profile's text for an alarm code, or "unknown alarm code N".
  std::string alarm_meaning(int code) const;
};

// One axis of a bench of two single-axis drives: its drive and, when the
// drive has a link of its own (`url` in its table), that link. Without one,
// the drive is reached at the bench URL with its own link.unit_id.
struct AxisDrive {
  DriveProfile drive;  // drive.axis is 'x' or 'y'
  std::optional<BenchUrl> url;
};

struct AxisDrives {
  AxisDrive x, y;
};

// Reads and validates a profile file (config/reader.hpp: a regular file of at
// most 1 MiB): one controller of both axes ([link], [registers], ...), or two
// single-axis drives ([x] and [y] tables, each with its own [link],
// [registers], ..., sharing [motion] and [soft_limits]; docs/drive-profile.md). Throws ProfileError
// "FILE: TABLE.KEY = VALUE: [PROBLEM; ]expected WHAT". The top-level [sim] table is the simulated
// bench's (sim/bench/config.hpp) and is not read here; any other unknown key or table, at the top
// or inside the profile's tables, is refused, so a typo never silently falls back to a default.
DriveProfile load_drive_profile(const std::string& path);
// The same for TOML text read from `source` (named in messages).
DriveProfile parse_drive_profile(std::string_view toml_text, const std::string& source);

// Checks a profile built in code the same way a file is checked. Throws
// ProfileError "SOURCE: FIELD = VALUE: [PROBLEM; ]expected WHAT" naming
// profile.source, the inconsistent field and its value.
void validate(const DriveProfile& profile);

// 32-bit two's complement value <-> two registers in the given word order.
void encode_int32(std::int32_t value, WordOrder order, std::uint16_t out[2]);
std::int32_t decode_int32(const std::uint16_t in[2], WordOrder order);

}  // namespace motion
