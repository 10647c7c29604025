// Against third-party Modbus peers, so that the map is standard Modbus and a
// profile really describes another drive:
//  - Debian's mbpoll reads and writes the simulated bench;
//  - a drive emulated with Debian's pymodbus (low word first, 0.01 mm, all
//    holding registers) is driven through its profile file;
//  - the simulated bench over Modbus RTU, through a socat pseudo-terminal pair.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <mutex>
#include <regex>
#include <thread>

#include "child_process.hpp"
#include "motion/errors.hpp"
#include "motion/modbus_link.hpp"
#include "pty_pair.hpp"
#include "sim_bench_fixture.hpp"

namespace {

using namespace std::chrono_literals;
using rig_test::ChildProcess;
using rig_test::SimBenchTest;

// mbpoll's "[address]: value" lines.
std::map<int, long> mbpoll_values(const std::string& out) {
  std::map<int, long> v;
  const std::regex line(R"(\[(\d+)\]:\s+(-?\d+))");
  for (std::sregex_iterator it(out.begin(), out.end(), line), end; it != end; ++it) {
    v[std::stoi((*it)[1])] = std::stol((*it)[2]);
  }
  return v;
}

std::string mbpoll(int port, const std::string& args) {
  int status = 0;
  const std::string out = rig_test::run_command(
      "mbpoll -m tcp -p " + std::to_string(port) + " -a 1 -0 -1 " + args + " 2>&1", &status);
  EXPECT_EQ(status, 0) << out;
  return out;
}

// Polls `done` every 5 ms for up to `timeout`. It returns as soon as `done`
// holds (moves here take a fraction of a second), so kEventually only bounds
// a broken test, with room for a loaded host or a sanitizer build.
constexpr auto kEventually = 20s;
template <class Pred>
bool eventually(Pred done, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
  return true;
}

class Mbpoll : public SimBenchTest {};

TEST_F(Mbpoll, WritesTargetsTheSimulatedBenchDecodes) {
  start_server();
  // int32, big-endian word order (-B), to holding registers 0..3.
  mbpoll(server_->port(), "-r 0 -t 4:int -B 127.0.0.1 -- 1000 2000");
  const auto written = server_->written_targets();
  ASSERT_EQ(written.size(), 1u);
  EXPECT_EQ(written[0].x_mm, 1.0);
  EXPECT_EQ(written[0].y_mm, 2.0);
}

TEST_F(Mbpoll, HomesMovesAndReadsBackTheSimulatedBench) {
  start_server();
  const int port = server_->port();
  mbpoll(port, "-r 5 -t 4 127.0.0.1 -- 2");  // command: home
  ASSERT_TRUE(eventually([&] { return server_->encoder_position_mm().x_mm == 0; }, kEventually));
  mbpoll(port, "-r 0 -t 4:int -B 127.0.0.1 -- 12345 -6789");  // targets, µm
  mbpoll(port, "-r 4 -t 4 127.0.0.1 -- 50 1");                // speed 50 mm/s, command: move
  // -6789 µm is outside the sim's Y travel (-5 mm): alarm 1, no motion.
  ASSERT_TRUE(eventually([&] { return mbpoll_values(mbpoll(port, "-r 5 -t 3 127.0.0.1"))[5] == 1; },
                         kEventually));
  mbpoll(port, "-r 4 -t 4 127.0.0.1 -- 50 4");  // reset alarm
  mbpoll(port, "-r 0 -t 4:int -B 127.0.0.1 -- 12345 -4321");
  mbpoll(port, "-r 4 -t 4 127.0.0.1 -- 50 1");
  ASSERT_TRUE(eventually(
      [&] { return std::fabs(server_->encoder_position_mm().y_mm + 4.321) < 1e-9; }, kEventually));
  auto feedback = mbpoll_values(mbpoll(port, "-r 0 -t 3:int -B -c 2 127.0.0.1"));
  EXPECT_EQ(feedback[0], 12345);
  EXPECT_EQ(feedback[2], -4321);
  ASSERT_TRUE(eventually(
      [&] {
        // status bits: homed (0) and in position (2)
        return mbpoll_values(mbpoll(port, "-r 4 -t 3 127.0.0.1"))[4] == 0b101;
      },
      kEventually));
}

// The emulator is a Python process; it prints "PORT n" once it listens.
class PymodbusDrive : public ::testing::Test {
 protected:
  void SetUp() override {
    drive_ = std::make_unique<ChildProcess>(std::vector<std::string>{
        "/usr/bin/python3", std::string(RIG_SOURCE_DIR) + "/tests/motion/pymodbus_drive.py", "0"});
    const auto line = drive_->read_line(kEventually);
    ASSERT_TRUE(line && line->rfind("PORT ", 0) == 0)
        << "pymodbus emulator did not start (python3-pymodbus installed?)";
    port_ = std::stoi(line->substr(5));
    profile_ = motion::load_drive_profile(std::string(RIG_SOURCE_DIR) +
                                          "/tests/motion/pymodbus_drive.toml");
  }
  std::unique_ptr<motion::ModbusBench> connect() {
    return std::make_unique<motion::ModbusBench>(
        motion::BenchUrl::parse("modbus-tcp://127.0.0.1:" + std::to_string(port_)), profile_);
  }

  std::unique_ptr<ChildProcess> drive_;
  int port_ = 0;
  motion::DriveProfile profile_;
};

TEST_F(PymodbusDrive, IsDrivenThroughItsProfile) {
  auto bench = connect();
  bench->home();
  bench->wait_settled(5s);
  bench->move_to(-12.34, 56.78);
  const motion::BenchStatus s = bench->wait_settled(5s);
  EXPECT_NEAR(s.position.x_mm, -12.34, 1e-9);
  EXPECT_NEAR(s.position.y_mm, 56.78, 1e-9);
  EXPECT_TRUE(s.in_position);

  // What the drive holds, read raw: low word first, 0.01 mm, two's complement.
  modbus_t* raw = modbus_new_tcp("127.0.0.1", port_);
  ASSERT_EQ(modbus_connect(raw), 0);
  std::uint16_t regs[6];
  ASSERT_EQ(modbus_read_registers(raw, 256, 6, regs), 6);
  modbus_close(raw);
  modbus_free(raw);
  const std::int32_t x = -1234;
  EXPECT_EQ(regs[0], static_cast<std::uint32_t>(x) & 0xFFFF);
  EXPECT_EQ(regs[1], static_cast<std::uint32_t>(x) >> 16);
  EXPECT_EQ(regs[2], 5678);
  EXPECT_EQ(regs[3], 0);
  EXPECT_EQ(regs[4], 20000);  // 200 mm/s in 0.01 mm/s
  EXPECT_EQ(regs[5], 17);     // the profile's move command
}

TEST_F(PymodbusDrive, AlarmMeaningComesFromTheProfile) {
  auto bench = connect();
  bench->move_to(1, 1);  // not homed
  try {
    bench->wait_settled(2s);
    FAIL();
  } catch (const motion::BenchFault& e) {
    EXPECT_EQ(e.code(), 4);
    EXPECT_EQ(e.meaning(), "home return incomplete");
  }
}

// Modbus RTU through a pseudo-terminal pair made by socat. Ptys ignore the
// baud rate: this checks RTU framing (CRC, unit id, silent intervals as seen
// by libmodbus), not serial timing.
class RtuOverPty : public SimBenchTest {
 protected:
  void TearDown() override { server_.reset(); }  // before the line goes

  const rig_test::PtyPair serial_;
  const std::string bench_ = serial_.drive_end();    // the simulated bench's end
  const std::string driver_ = serial_.driver_end();  // the driver's end
};

TEST_F(RtuOverPty, SimulatedBenchIsDrivenOverRtu) {
  options_.rtu_device = bench_;
  start_server();
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=115200&parity=N&stop=1&unit=1"),
      profile_);
  bench.home();
  bench.wait_settled(5s);
  bench.move_to(7.5, 2.25);
  const motion::BenchStatus s = bench.wait_settled(5s);
  EXPECT_NEAR(s.position.x_mm, 7.5, 1e-9);
  EXPECT_NEAR(s.position.y_mm, 2.25, 1e-9);
}

// On a serial line a reply that comes after the response timeout is still on
// its way when the driver asks again, and Modbus RTU has no transaction id to
// tell it from the answer to the next request: taken for it, every request
// after reads the reply to the one before (the wrong function: invalid data;
// the same read: old values). The drive answers the write that starts a move
// 1.5 response timeouts late: the driver drops that reply, reconnects and
// the move completes on the target.
TEST_F(RtuOverPty, AReplyPastTheTimeoutIsNotTakenForTheNextAnswer) {
  options_.rtu_device = bench_;
  start_server();
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=115200&parity=N"), profile_);
  bench.home();
  bench.wait_settled(5s);
  sim::bench::FaultPlan faults;
  faults.late_after_requests = 1;
  faults.late_ms = 1.5 * profile_.timing.response_timeout_ms;
  server_->inject(faults);
  bench.move_to(30, 20);
  const motion::BenchStatus s = bench.wait_settled(5s);
  EXPECT_NEAR(s.position.x_mm, 30, 1e-9);
  EXPECT_NEAR(s.position.y_mm, 20, 1e-9);
  EXPECT_GE(bench.reconnects(), 1);
}

TEST_F(RtuOverPty, RequestsForAnotherUnitAreNotAnswered) {
  options_.rtu_device = bench_;
  start_server();
  profile_.timing.reconnect_timeout_ms = 200;
  try {
    motion::ModbusBench bench(
        motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=115200&parity=N&unit=7"),
        profile_);
    FAIL() << "unit 7 answered; the simulated bench is unit 1";
  } catch (const motion::BenchLinkError& e) {
    // The message names the unit and the serial settings to check.
    const std::string what = e.what();
    EXPECT_NE(what.find("no answer from unit 7 on " + driver_ +
                        " at 115200 baud, parity N, 8 data and 2 stop bits"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("check the drive's unit id"), std::string::npos) << what;
  }
}

TEST_F(RtuOverPty, TheUrlsBaudAndStopBitsReachTheSerialLine) {
  // A pty carries bytes whatever its settings, so the bench still answers;
  // what the URL set is read back from the line's termios. A mismatched baud
  // rate cannot be shown on a pty (it ignores the rate); on a real line it
  // garbles or loses the answers, which the driver reports as such.
  options_.rtu_device = bench_;
  start_server();
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=38400&parity=E&stop=2"), profile_);
  EXPECT_FALSE(bench.status().alarm);
  const int fd = open(driver_.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  termios line{};
  ASSERT_EQ(tcgetattr(fd, &line), 0);
  close(fd);
  EXPECT_EQ(cfgetospeed(&line), static_cast<speed_t>(B38400));
  EXPECT_EQ(cfgetispeed(&line), static_cast<speed_t>(B38400));
  EXPECT_TRUE(line.c_cflag & CSTOPB);  // 2 stop bits
  // Parity cannot be read back here: Linux's pty driver forces CS8 without
  // PARENB whatever is set (drivers/tty/pty.c, pty_set_termios).
}

// The silent interval of 3.5 characters the Modbus serial spec asks between
// frames (V1.02, 2.5.1.1), at the URL's settings: 1 start, 8 data, parity and
// stop bits a character; 1750 us above 19200 baud.
TEST(RtuTiming, TheSilentIntervalFollowsTheUrlsBaudParityAndStopBits) {
  using std::chrono::microseconds;
  auto silence = [](const std::string& query) {
    return motion::ModbusLink::frame_silence(
        motion::BenchUrl::parse("modbus-rtu:///dev/ttyS0?" + query));
  };
  EXPECT_EQ(silence("baud=9600&parity=E&stop=1"), microseconds(4011));   // 3.5 * 11 / 9600 s
  EXPECT_EQ(silence("baud=9600&parity=N&stop=1"), microseconds(3646));   // 3.5 * 10 / 9600 s
  EXPECT_EQ(silence("baud=19200&parity=N"), microseconds(2006));         // 8N2: 11 bits
  EXPECT_EQ(silence("baud=38400&parity=N&stop=1"), microseconds(1750));  // fixed above 19200
  EXPECT_EQ(motion::ModbusLink::frame_silence(motion::BenchUrl::parse("modbus-tcp://h:502")),
            microseconds(0));
}

// A Modbus RTU peer on the bench end of the pty pair, run on a thread of the
// test: `serve` is called whenever bytes can be read from the line, until the
// peer is destroyed.
class PtyPeer {
 public:
  template <class Serve>
  PtyPeer(modbus_t* ctx, Serve serve) : ctx_(ctx) {
    thread_ = std::thread([this, serve] {
      const int fd = modbus_get_socket(ctx_);
      while (!stop_) {
        pollfd p{fd, POLLIN, 0};
        if (poll(&p, 1, 20) == 1) serve(ctx_);
      }
    });
  }
  ~PtyPeer() {
    stop_ = true;
    thread_.join();
    modbus_close(ctx_);
    modbus_free(ctx_);
  }

 private:
  modbus_t* ctx_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

TEST_F(RtuOverPty, LinksToTwoUnitsOnOneDeviceShareOnePort) {
  // Two drives on one RS-485 line: one open port, so that the silent
  // interval is kept between frames to different units, and a port closed
  // after a link error is closed for both.
  const std::string line = "modbus-rtu://" + driver_ + "?baud=9600&parity=E&stop=1";
  motion::ModbusLink x(motion::BenchUrl::parse(line + "&unit=1"), 1, 200ms);
  motion::ModbusLink y(motion::BenchUrl::parse(line + "&unit=2"), 2, 200ms);
  EXPECT_FALSE(y.connected());
  ASSERT_EQ(x.connect(), 0);
  EXPECT_TRUE(y.connected());
  y.close();
  EXPECT_FALSE(x.connected());
  // Other serial settings on the same device are refused, naming both.
  try {
    motion::ModbusLink z(
        motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=19200&parity=E&unit=3"), 3,
        200ms);
    FAIL() << "a second link at 19200 baud joined a line at 9600 baud";
  } catch (const motion::ProfileError& e) {
    EXPECT_NE(std::string(e.what()).find(driver_ +
                                         " is already in use at other serial "
                                         "settings (modbus-rtu://" +
                                         driver_ + "?baud=9600"),
              std::string::npos)
        << e.what();
  }
}

TEST_F(RtuOverPty, TheSilentIntervalIsKeptBetweenFramesToTwoUnitsOnOneLine) {
  // A real libmodbus RTU server at unit 1 stamps when its answer starts to go
  // and when each request has arrived, also one for unit 2, which nobody on the
  // line answers. As below, a request to unit 2 that left the driver the
  // silent interval after it received unit 1's answer arrives at least that
  // long after the answer went, with no tolerance needed. With a port per
  // unit, each knew only its own frames, so the request to unit 2 could
  // follow unit 1's answer at once (and on a pty the second open of the
  // device fails). (After a request for another unit a libmodbus
  // server takes the next frame for that unit's answer and ignores it: a
  // server per round.)
  using Clock = std::chrono::steady_clock;
  struct Frame {
    int unit;  // of a request; 0 for an answer
    Clock::time_point at;
  };
  std::mutex mutex;
  std::vector<Frame> frames;
  const std::string line = "modbus-rtu://" + driver_ + "?baud=9600&parity=E&stop=1";
  motion::ModbusLink x(motion::BenchUrl::parse(line + "&unit=1"), 1, 200ms);
  // Unit 2 never answers: a short wait for it (it then closes the line).
  motion::ModbusLink y(motion::BenchUrl::parse(line + "&unit=2"), 2, 30ms);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, 16, 16);
  for (int round = 0; round < 3; ++round) {
    modbus_t* ctx = modbus_new_rtu(bench_.c_str(), 9600, 'E', 8, 1);
    ASSERT_NE(ctx, nullptr);
    modbus_set_slave(ctx, 1);
    ASSERT_EQ(modbus_connect(ctx), 0);
    PtyPeer peer(ctx, [&](modbus_t* c) {
      std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
      const int n = modbus_receive(c, query);  // 0: a whole request for another unit
      const auto in = Clock::now();
      if (n < 0) return;
      std::lock_guard<std::mutex> lock(mutex);
      frames.push_back({query[0], in});
      if (n > 0) {
        // Stamped before the answer is written, so never later than the
        // driver can have it, however long this thread waits for a core.
        const auto answering = Clock::now();
        modbus_reply(c, query, n, map);
        frames.push_back({0, answering});
      }
    });
    std::uint16_t value = 0;
    ASSERT_EQ(x.connect(), 0);
    EXPECT_EQ(x.read(motion::RegisterTable::kHolding, 0, 1, &value), 0);
    EXPECT_EQ(y.read(motion::RegisterTable::kHolding, 0, 1, &value), ETIMEDOUT);
  }
  modbus_mapping_free(map);
  const auto silence = std::chrono::microseconds(4011);  // 3.5 characters at 9600 baud 8E1
  int checked = 0;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (frames[i - 1].unit != 0 || frames[i].unit != 2) continue;
    ++checked;
    EXPECT_GE(frames[i].at - frames[i - 1].at, silence)
        << "the request to unit 2 came "
        << std::chrono::duration_cast<std::chrono::microseconds>(frames[i].at - frames[i - 1].at)
               .count()
        << " us after unit 1's answer";
  }
  EXPECT_EQ(checked, 3);
}

TEST_F(RtuOverPty, RequestsWaitTheSilentIntervalAfterEachAnswer) {
  // A real libmodbus RTU server (unit 1, every register kept) stamps when a
  // request has arrived and when its answer starts to go. A request leaves the
  // driver at least the silent interval after the driver received the last
  // answer, which is after the server began to send it: every gap the server
  // sees is at least the interval, with no tolerance needed, however the
  // threads are scheduled (each stamp errs on the side of a longer gap).
  // Without the wait, requests arrived 0.08 to 0.34 ms after the last answer
  // (measured), a tenth of it.
  // A pty ignores the baud rate, so only the driver's pacing is tested here.
  modbus_t* ctx = modbus_new_rtu(bench_.c_str(), 9600, 'E', 8, 1);
  ASSERT_NE(ctx, nullptr);
  modbus_set_slave(ctx, 1);
  ASSERT_EQ(modbus_connect(ctx), 0);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, 16, 16);
  using Clock = std::chrono::steady_clock;
  std::mutex mutex;
  std::vector<std::pair<Clock::time_point, Clock::time_point>> frames;  // (request in, answer out)
  {
    PtyPeer peer(ctx, [&](modbus_t* c) {
      std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
      const int n = modbus_receive(c, query);
      if (n <= 0) return;
      const auto in = Clock::now();
      // Stamped before the answer is written (see above): a stamp after it
      // came up to 1.7 ms late on a loaded machine, which read as a request
      // sent too early.
      const auto answering = Clock::now();
      modbus_reply(c, query, n, map);
      std::lock_guard<std::mutex> lock(mutex);
      frames.push_back({in, answering});
    });
    motion::ModbusBench bench(
        motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=9600&parity=E&stop=1"),
        profile_);
    bench.status();
    bench.move_to(1, 2);  // targets written and read back, the command written and read back
    bench.status();
  }
  modbus_mapping_free(map);
  const auto silence = std::chrono::microseconds(4011);
  ASSERT_GE(frames.size(), 6u);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    EXPECT_GE(frames[i].first - frames[i - 1].second, silence)
        << "request " << i << " came "
        << std::chrono::duration_cast<std::chrono::microseconds>(frames[i].first -
                                                                 frames[i - 1].second)
               .count()
        << " us after the last answer";
  }
}

// Modbus CRC-16 (polynomial 0xA001 reflected, initial 0xFFFF), low byte first
// on the line.
std::uint16_t modbus_crc(const std::uint8_t* data, std::size_t n) {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= data[i];
    for (int b = 0; b < 8; ++b)
      crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001) : crc >> 1;
  }
  return crc;
}

TEST_F(RtuOverPty, AnAnswerFromAnotherUnitIsRefusedNamingBothUnits) {
  // The peer answers every read as unit 2, in well-formed frames with a right
  // CRC: only the unit id is wrong, and the driver must not take the answer.
  modbus_t* ctx = modbus_new_rtu(bench_.c_str(), 19200, 'E', 8, 1);
  ASSERT_NE(ctx, nullptr);
  ASSERT_EQ(modbus_connect(ctx), 0);
  std::atomic<int> answered{0};
  PtyPeer peer(ctx, [&](modbus_t* c) {
    const int fd = modbus_get_socket(c);
    std::uint8_t req[8];
    std::size_t got = 0;
    while (got < sizeof req) {  // a read request is 8 bytes; the driver sends it at once
      pollfd p{fd, POLLIN, 0};
      if (poll(&p, 1, 50) != 1) return;
      const ssize_t n = ::read(fd, req + got, sizeof req - got);
      if (n <= 0) return;
      got += static_cast<std::size_t>(n);
    }
    const int count = (req[4] << 8) | req[5];
    std::vector<std::uint8_t> answer = {2, req[1], static_cast<std::uint8_t>(2 * count)};
    answer.resize(3 + 2 * count, 0);
    const std::uint16_t crc = modbus_crc(answer.data(), answer.size());
    answer.push_back(crc & 0xFF);
    answer.push_back(crc >> 8);
    if (::write(fd, answer.data(), answer.size()) == static_cast<ssize_t>(answer.size())) {
      ++answered;
    }
  });
  profile_.timing.reconnect_timeout_ms = 300;
  try {
    motion::ModbusBench bench(
        motion::BenchUrl::parse("modbus-rtu://" + driver_ + "?baud=19200&parity=E&unit=1"),
        profile_);
    FAIL() << "an answer from unit 2 was taken for unit 1's";
  } catch (const motion::BenchLinkError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("the answer came from unit 2, not from unit 1 that was asked, and is "
                        "refused"),
              std::string::npos)
        << what;
  }
  EXPECT_GE(answered.load(), 1);
}

}  // namespace
