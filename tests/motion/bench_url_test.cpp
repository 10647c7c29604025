// Bench URLs: TCP and RTU forms, defaults, and the exact error for bad ones.
#include "motion/bench_url.hpp"

#include <gtest/gtest.h>

#include "motion/errors.hpp"

namespace {

using motion::BenchUrl;

TEST(BenchUrl, ParsesTcpHostAndPort) {
  const BenchUrl u = BenchUrl::parse("modbus-tcp://192.168.1.20:502?unit=3");
  EXPECT_EQ(u.transport, BenchUrl::Transport::kTcp);
  EXPECT_EQ(u.host, "192.168.1.20");
  EXPECT_EQ(u.port, 502);
  EXPECT_EQ(u.unit, 3);
}

TEST(BenchUrl, ParsesRtuDeviceAndLineSettings) {
  const BenchUrl u = BenchUrl::parse("modbus-rtu:///dev/ttyUSB0?baud=115200&parity=N&unit=1");
  EXPECT_EQ(u.transport, BenchUrl::Transport::kRtu);
  EXPECT_EQ(u.device, "/dev/ttyUSB0");
  EXPECT_EQ(u.baud, 115200);
  EXPECT_EQ(u.parity, 'N');
  EXPECT_EQ(u.data_bits, 8);
  EXPECT_EQ(u.stop_bits, 2);  // no parity: two stop bits, as the Modbus serial spec asks
  EXPECT_EQ(u.unit, 1);
}

TEST(BenchUrl, RtuDefaultsAreTheModbusSerialDefaults) {
  const BenchUrl u = BenchUrl::parse("modbus-rtu:///dev/ttyS1");
  EXPECT_EQ(u.baud, 19200);
  EXPECT_EQ(u.parity, 'E');
  EXPECT_EQ(u.stop_bits, 1);
  EXPECT_FALSE(u.unit.has_value());
}

TEST(BenchUrl, UnknownSchemeIsRefused) {
  EXPECT_THROW(BenchUrl::parse("tcp://host:502"), motion::ProfileError);
}

TEST(BenchUrl, BadPortIsRefusedByName) {
  try {
    BenchUrl::parse("modbus-tcp://host:99999");
    FAIL();
  } catch (const motion::ProfileError& e) {
    EXPECT_STREQ(e.what(),
                 "bench URL modbus-tcp://host:99999: port \"99999\" is not an integer in 1..65535");
  }
}

TEST(BenchUrl, UnknownQueryKeyIsRefused) {
  EXPECT_THROW(BenchUrl::parse("modbus-rtu:///dev/ttyS0?speed=9600"), motion::ProfileError);
}

}  // namespace
