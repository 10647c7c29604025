// Against third-party Modbus peers, so that the map is standard Modbus and a
// profile really describes another drive:
//  - Debian's mbpoll reads and writes the simulated bench;
//  - a drive emulated with Debian's pymodbus (low word first, 0.01 mm, all
//    holding registers) is driven through its profile file;
//  - the simulated bench over Modbus RTU, through a socat pseudo-terminal pair.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <map>
#include <regex>
#include <thread>

#include "child_process.hpp"
#include "motion/errors.hpp"
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
  void SetUp() override {
    char dir_template[] = "/tmp/rig-rtu-XXXXXX";
    ASSERT_NE(mkdtemp(dir_template), nullptr);
    dir_ = dir_template;
    socat_ = std::make_unique<ChildProcess>(
        std::vector<std::string>{"socat", "pty,raw,echo=0,link=" + dir_ + "/bench",
                                 "pty,raw,echo=0,link=" + dir_ + "/driver"});
    struct stat st;
    ASSERT_TRUE(eventually(
        [&] {
          return stat((dir_ + "/bench").c_str(), &st) == 0 &&
                 stat((dir_ + "/driver").c_str(), &st) == 0;
        },
        kEventually))
        << "socat made no pty pair";
  }
  void TearDown() override {
    server_.reset();
    socat_.reset();
    std::system(("rm -rf " + dir_).c_str());
  }

  std::string dir_;
  std::unique_ptr<ChildProcess> socat_;
};

TEST_F(RtuOverPty, SimulatedBenchIsDrivenOverRtu) {
  options_.rtu_device = dir_ + "/bench";
  start_server();
  motion::ModbusBench bench(motion::BenchUrl::parse("modbus-rtu://" + dir_ +
                                                    "/driver?baud=115200&parity=N&stop=1&unit=1"),
                            profile_);
  bench.home();
  bench.wait_settled(5s);
  bench.move_to(7.5, 2.25);
  const motion::BenchStatus s = bench.wait_settled(5s);
  EXPECT_NEAR(s.position.x_mm, 7.5, 1e-9);
  EXPECT_NEAR(s.position.y_mm, 2.25, 1e-9);
}

TEST_F(RtuOverPty, RequestsForAnotherUnitAreNotAnswered) {
  options_.rtu_device = dir_ + "/bench";
  start_server();
  profile_.timing.reconnect_timeout_ms = 200;
  try {
    motion::ModbusBench bench(
        motion::BenchUrl::parse("modbus-rtu://" + dir_ + "/driver?baud=115200&parity=N&unit=7"),
        profile_);
    FAIL() << "unit 7 answered; the simulated bench is unit 1";
  } catch (const motion::BenchLinkError& e) {
    // The message names the unit and the serial settings to check.
    const std::string what = e.what();
    EXPECT_NE(what.find("no answer from unit 7 on " + dir_ +
                        "/driver at 115200 baud, parity N, 8 data and 2 stop bits"),
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
  options_.rtu_device = dir_ + "/bench";
  start_server();
  motion::ModbusBench bench(
      motion::BenchUrl::parse("modbus-rtu://" + dir_ + "/driver?baud=38400&parity=E&stop=2"),
      profile_);
  EXPECT_FALSE(bench.status().alarm);
  const int fd = open((dir_ + "/driver").c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK);
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

}  // namespace
