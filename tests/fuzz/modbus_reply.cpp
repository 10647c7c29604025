// Modbus replies from a hostile or broken drive: a loopback TCP peer answers
// every request of motion::ModbusBench with a reply the fuzz input scripts,
// while the driver connects, reads the bench state, sets the speed, moves,
// waits, homes, resets an alarm and stops. Each operation either works or
// throws one of the driver's documented errors (motion::BenchError and its
// kinds); anything else escaping, a crash or a sanitizer report is a finding.
//
// Input: byte 0 picks the drive conventions (position width, word order,
// handshake, servo-on, reset pulse), so that every decoding path is reached;
// then one reply per request, each a mode byte and what the mode needs:
//   mode 0  a well-formed reply: read -> byte count and the requested
//           registers (values from the input, zeros past its end); write ->
//           the request echoed
//   mode 1  an exception reply, code from the next byte
//   mode 2  N (next byte) raw bytes as the whole frame, header included
//   mode 3  a valid header and transaction id with N raw bytes of PDU
// When the script has run out, the peer closes the connection.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <mutex>
#include <thread>
#include <vector>

#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"
#include "motion/errors.hpp"
#include "motion/modbus_bench.hpp"

namespace {

using namespace std::chrono_literals;

// The input being served, shared with the peer's thread.
struct Script {
  std::mutex mutex;
  std::vector<std::uint8_t> bytes;
  std::size_t next = 0;

  // The next byte, or -1 at the end.
  int take() {
    if (next >= bytes.size()) return -1;
    return bytes[next++];
  }
};
Script script;

bool read_all(int fd, std::uint8_t* out, std::size_t n) {
  while (n > 0) {
    const ssize_t got = ::read(fd, out, n);
    if (got <= 0) return false;
    out += got;
    n -= static_cast<std::size_t>(got);
  }
  return true;
}

// The reply to one request (MBAP header + PDU), or empty to close.
std::vector<std::uint8_t> reply_to(const std::vector<std::uint8_t>& request) {
  std::lock_guard<std::mutex> lock(script.mutex);
  const int mode = script.take();
  if (mode < 0) return {};
  std::vector<std::uint8_t> pdu;
  const std::uint8_t function = request[7];
  switch (mode % 4) {
    case 0:
      if ((function == 3 || function == 4) && request.size() >= 12) {
        const int count = std::min(request[10] << 8 | request[11], 125);
        pdu = {function, static_cast<std::uint8_t>(2 * count)};
        for (int i = 0; i < 2 * count; ++i)
          pdu.push_back(static_cast<std::uint8_t>(std::max(script.take(), 0)));
      } else {
        pdu.assign(request.begin() + 7,
                   request.begin() + std::min<std::size_t>(request.size(), 12));
      }
      break;
    case 1:
      pdu = {static_cast<std::uint8_t>(function | 0x80),
             static_cast<std::uint8_t>(std::max(script.take(), 0))};
      break;
    case 2: {
      std::vector<std::uint8_t> raw;
      for (int n = std::max(script.take(), 0); n > 0; --n)
        raw.push_back(static_cast<std::uint8_t>(std::max(script.take(), 0)));
      return raw.empty() ? std::vector<std::uint8_t>{0} : raw;
    }
    default:
      for (int n = std::max(script.take(), 0); n > 0; --n)
        pdu.push_back(static_cast<std::uint8_t>(std::max(script.take(), 0)));
  }
  const std::size_t length = pdu.size() + 1;  // unit id + PDU
  std::vector<std::uint8_t> frame = {request[0],
                                     request[1],
                                     0,
                                     0,
                                     static_cast<std::uint8_t>(length >> 8),
                                     static_cast<std::uint8_t>(length & 0xff),
                                     request[6]};
  frame.insert(frame.end(), pdu.begin(), pdu.end());
  return frame;
}

// One connection: request, scripted reply, until either side closes.
void serve(int fd) {
  for (;;) {
    std::vector<std::uint8_t> request(7);
    if (!read_all(fd, request.data(), 7)) break;
    const std::size_t length = static_cast<std::size_t>(request[4] << 8 | request[5]);
    if (length < 2 || length > 260) break;
    request.resize(6 + length);
    if (!read_all(fd, request.data() + 7, length - 1)) break;
    const std::vector<std::uint8_t> reply = reply_to(request);
    if (reply.empty() || ::write(fd, reply.data(), reply.size()) < 0) break;
  }
  ::close(fd);
}

// The peer: listens on an ephemeral loopback port for the whole run.
int start_peer() {
  const int listener = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  if (listener < 0 || ::bind(listener, reinterpret_cast<sockaddr*>(&address), size) != 0 ||
      ::listen(listener, 4) != 0 ||
      ::getsockname(listener, reinterpret_cast<sockaddr*>(&address), &size) != 0)
    std::abort();
  std::thread([listener] {
    for (;;) {
      const int fd = ::accept(listener, nullptr, nullptr);
      if (fd >= 0) serve(fd);
    }
  }).detach();
  return ntohs(address.sin_port);
}

// The simulated bench's profile with every wait cut to milliseconds, and the
// conventions byte 0 picks.
motion::DriveProfile profile_for(std::uint8_t conventions) {
  static const motion::DriveProfile base =
      motion::load_drive_profile(std::string(RIG_SOURCE_DIR) + "/config/benches/sim.toml");
  motion::DriveProfile p = base;
  p.timing.response_timeout_ms = 5;
  p.timing.reconnect_timeout_ms = 0;
  p.timing.poll_interval_ms = 1;
  p.timing.settle_time_ms = 1;
  p.timing.settle_timeout_ms = 5;
  p.timing.home_timeout_ms = 5;
  p.protocol.accept_timeout_ms = 3;
  p.protocol.pulse_ms = 1;
  if (conventions & 1) p.position_bits = 16;
  if (conventions & 2) p.word_order = motion::WordOrder::kLowFirst;
  p.protocol.handshake = (conventions >> 2) % 3 == 0   ? motion::CommandHandshake::kKept
                         : (conventions >> 2) % 3 == 1 ? motion::CommandHandshake::kSelfClearing
                                                       : motion::CommandHandshake::kPulse;
  if (conventions & 16) p.protocol.ack_bit = 5;
  if (conventions & 32) {
    p.protocol.servo_on = 0x100;
    p.protocol.servo_ready_bit = 6;
  }
  p.protocol.reset_pulse = (conventions & 64) != 0;
  return p;
}

template <class Op>
void attempt(Op op) {
  try {
    op();
  } catch (const motion::BenchError&) {
    // Documented: a fault, timeout, link error or refused write.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const int port = start_peer();
  if (size == 0) return 0;
  {
    std::lock_guard<std::mutex> lock(script.mutex);
    script.bytes.assign(data + 1, data + size);
    script.next = 0;
  }
  const motion::BenchUrl url =
      motion::BenchUrl::parse("modbus-tcp://127.0.0.1:" + std::to_string(port));
  try {
    motion::ModbusBench bench(url, profile_for(data[0]));
    attempt([&] { (void)bench.status(); });
    attempt([&] { (void)bench.position(); });
    attempt([&] { bench.set_speed(40); });
    attempt([&] { bench.move_to(120.5, 80.25); });
    attempt([&] { (void)bench.wait_settled(5ms); });
    attempt([&] { bench.home(); });
    attempt([&] { bench.reset_alarm(); });
    attempt([&] { bench.stop(); });
  } catch (const motion::BenchError&) {
    // The first connection's state read failed: documented.
  }
  return 0;
}
