// vision::CameraClock on synthetic readings: a camera whose counter runs
// 1,000,000,000 ns behind the host, read with known brackets and latencies.
#include "vision/camera_clock.hpp"

#include <gtest/gtest.h>

#include <cstdlib>

namespace {

constexpr int64_t kTrueOffset = 1'000'000'000;  // host = camera + 1 s

TEST(CameraClock, NothingIsMappedBeforeAnyReading) {
  const vision::CameraClock clock;
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kNone);
  EXPECT_FALSE(clock.to_host_ns(5).has_value());
  EXPECT_EQ(clock.describe(), "none");
}

// The latch happened somewhere in [h0, h1]: the midpoint is within half the
// bracket (plus a tick) of the truth, and the narrowest bracket wins.
TEST(CameraClock, LatchTakesTheMidpointOfTheNarrowestBracket) {
  vision::CameraClock clock;
  // Latched 300 µs into a 1 ms bracket: the midpoint is 200 µs off.
  const int64_t camera = 5'000'000'000;
  clock.add_latch(camera + kTrueOffset - 300'000, camera, camera + kTrueOffset + 700'000, 8);
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kLatch);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 200'000);
  EXPECT_EQ(clock.error_bound_ns(), 500'008);
  EXPECT_LE(std::abs(clock.offset_ns() - kTrueOffset), clock.error_bound_ns());
  // A 100 µs bracket replaces it; a wider one later does not.
  clock.add_latch(camera + kTrueOffset - 40'000, camera, camera + kTrueOffset + 60'000, 8);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 10'000);
  EXPECT_EQ(clock.error_bound_ns(), 50'008);
  clock.add_latch(camera + kTrueOffset - 2'000'000, camera, camera + kTrueOffset, 8);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 10'000);
  // Arrivals never override a latch.
  clock.add_arrival(camera, camera + kTrueOffset + 1);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 10'000);
  EXPECT_EQ(*clock.to_host_ns(7), 7 + kTrueOffset + 10'000);
  EXPECT_EQ(clock.describe(), "latch, +- 0.050 ms");
}

// A frame arrives its latency after its exposure started: the smallest
// latency seen (here 3 ms) is how late the mapped times are, never early.
TEST(CameraClock, ArrivalKeepsTheSmallestLatency) {
  vision::CameraClock clock;
  for (const int64_t latency : {12'000'000, 3'000'000, 7'000'000}) {
    const int64_t camera = 10'000'000'000 + 100 * latency;
    clock.add_arrival(camera, camera + kTrueOffset + latency);
  }
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kArrival);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 3'000'000);
  EXPECT_EQ(*clock.to_host_ns(0), kTrueOffset + 3'000'000);
  // A latch, when one comes, replaces the arrival bound.
  clock.add_latch(kTrueOffset, 0, kTrueOffset + 2, 1);
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kLatch);
  EXPECT_EQ(clock.offset_ns(), kTrueOffset + 1);
}

TEST(CameraClock, ABracketRunningBackwardsIsIgnored) {
  vision::CameraClock clock;
  clock.add_latch(100, 0, 50);  // the host clock stepped between the two reads
  EXPECT_EQ(clock.method(), vision::CameraClock::Method::kNone);
}

}  // namespace
