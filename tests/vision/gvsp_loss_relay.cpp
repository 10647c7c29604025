#include "gvsp_loss_relay.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace vision_test {
namespace {

// GigE Vision: the control port, the write-register command and the
// bootstrap registers of stream channel 0's destination.
constexpr std::uint16_t kGvcpPort = 3956;
constexpr std::uint16_t kWriteRegisterCommand = 0x0082;
constexpr std::uint32_t kStreamChannel0Port = 0x0D00;     // SCP0: host port in bits 15..0
constexpr std::uint32_t kStreamChannel0Address = 0x0D18;  // SCDA0: IPv4 address
constexpr int kGvcpHeaderBytes = 8;
constexpr int kGvspHeaderBytes = 8;
constexpr std::uint8_t kGvspExtendedId = 0x80;  // packet format byte: 64-bit ids follow
constexpr std::uint8_t kGvspTrailer = 0x02;     // packet format byte, low nibble

std::uint32_t read_be32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) |
         p[3];
}

void write_be32(std::uint8_t* p, std::uint32_t v) {
  p[0] = static_cast<std::uint8_t>(v >> 24);
  p[1] = static_cast<std::uint8_t>(v >> 16);
  p[2] = static_cast<std::uint8_t>(v >> 8);
  p[3] = static_cast<std::uint8_t>(v);
}

sockaddr_in ipv4(const std::string& address, std::uint16_t port) {
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(port);
  if (inet_pton(AF_INET, address.c_str(), &a.sin_addr) != 1)
    throw std::runtime_error("GvspLossRelay: '" + address + "' is not an IPv4 address");
  return a;
}

// A UDP socket bound to `at`; returns the descriptor.
int bound_udp_socket(const sockaddr_in& at) {
  const int fd = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw std::runtime_error("GvspLossRelay: socket() failed");
  if (bind(fd, reinterpret_cast<const sockaddr*>(&at), sizeof at) != 0) {
    const int error = errno;
    close(fd);
    char text[INET_ADDRSTRLEN] = "?";
    inet_ntop(AF_INET, &at.sin_addr, text, sizeof text);
    throw std::runtime_error("GvspLossRelay: cannot bind " + std::string(text) + ":" +
                             std::to_string(ntohs(at.sin_port)) + " (" + std::strerror(error) +
                             ")");
  }
  return fd;
}

sockaddr_in local_address(int fd) {
  sockaddr_in a{};
  socklen_t length = sizeof a;
  getsockname(fd, reinterpret_cast<sockaddr*>(&a), &length);
  return a;
}

}  // namespace

GvspLossRelay::GvspLossRelay(const std::string& camera_address, const std::string& relay_address,
                             std::vector<Loss> losses)
    : losses_(std::move(losses)), camera_control_(ipv4(camera_address, kGvcpPort)) {
  try {
    control_fd_ = bound_udp_socket(ipv4(relay_address, kGvcpPort));
    upstream_fd_ = bound_udp_socket(ipv4("127.0.0.1", 0));
    stream_fd_ = bound_udp_socket(ipv4("127.0.0.1", 0));
    if (pipe2(wake_, O_CLOEXEC) != 0) throw std::runtime_error("GvspLossRelay: pipe2() failed");
  } catch (...) {
    for (int fd : {control_fd_, upstream_fd_, stream_fd_})
      if (fd >= 0) close(fd);
    throw;
  }
  // Whole frames may arrive while this thread is descheduled: the kernel
  // caps the request at net.core.rmem_max.
  const int buffer_bytes = 4 * 1024 * 1024;
  setsockopt(stream_fd_, SOL_SOCKET, SO_RCVBUF, &buffer_bytes, sizeof buffer_bytes);
  thread_ = std::thread([this] { run(); });
}

GvspLossRelay::~GvspLossRelay() {
  const char byte = 1;
  [[maybe_unused]] const ssize_t woken = write(wake_[1], &byte, 1);
  thread_.join();
  for (int fd : {control_fd_, upstream_fd_, stream_fd_, wake_[0], wake_[1]})
    close(fd);
}

bool GvspLossRelay::stream_redirected() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return stream_redirected_;
}

std::vector<GvspLossRelay::FrameTally> GvspLossRelay::frames() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return frames_;
}

int GvspLossRelay::unknown_packets() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return unknown_packets_;
}

void GvspLossRelay::run() {
  pollfd fds[4] = {{wake_[0], POLLIN, 0},
                   {control_fd_, POLLIN, 0},
                   {upstream_fd_, POLLIN, 0},
                   {stream_fd_, POLLIN, 0}};
  for (;;) {
    if (poll(fds, 4, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (fds[0].revents != 0) return;
    // The stream first: it is what must not back up.
    if (fds[3].revents & POLLIN) relay_stream_packet();
    if (fds[1].revents & POLLIN) relay_control_from_client();
    if (fds[2].revents & POLLIN) relay_control_from_camera();
  }
}

void GvspLossRelay::relay_control_from_client() {
  std::uint8_t packet[1500];
  sockaddr_in from{};
  socklen_t from_length = sizeof from;
  const ssize_t n = recvfrom(control_fd_, packet, sizeof packet, 0,
                             reinterpret_cast<sockaddr*>(&from), &from_length);
  if (n <= 0) return;
  client_control_ = from;
  redirect_stream_destination(packet, n);
  sendto(upstream_fd_, packet, static_cast<size_t>(n), 0,
         reinterpret_cast<const sockaddr*>(&camera_control_), sizeof camera_control_);
}

void GvspLossRelay::relay_control_from_camera() {
  std::uint8_t packet[1500];
  const ssize_t n = recv(upstream_fd_, packet, sizeof packet, 0);
  if (n <= 0 || client_control_.sin_family != AF_INET) return;
  sendto(control_fd_, packet, static_cast<size_t>(n), 0,
         reinterpret_cast<const sockaddr*>(&client_control_), sizeof client_control_);
}

// A write-register command carries (address, value) pairs after its header;
// the stream destination's pairs are remembered and replaced by the relay's.
void GvspLossRelay::redirect_stream_destination(std::uint8_t* packet, long size) {
  if (size < kGvcpHeaderBytes) return;
  const std::uint16_t command = static_cast<std::uint16_t>((packet[2] << 8) | packet[3]);
  if (command != kWriteRegisterCommand) return;
  const sockaddr_in relay_stream = local_address(stream_fd_);
  for (long at = kGvcpHeaderBytes; at + 8 <= size; at += 8) {
    const std::uint32_t address = read_be32(packet + at);
    const std::uint32_t value = read_be32(packet + at + 4);
    if (address == kStreamChannel0Address) {
      client_stream_.sin_family = AF_INET;
      client_stream_.sin_addr.s_addr = htonl(value);
      write_be32(packet + at + 4, ntohl(relay_stream.sin_addr.s_addr));
    } else if (address == kStreamChannel0Port) {
      client_stream_.sin_port = htons(static_cast<std::uint16_t>(value & 0xFFFF));
      write_be32(packet + at + 4, (value & 0xFFFF0000u) | ntohs(relay_stream.sin_port));
      std::lock_guard<std::mutex> lock(mutex_);
      stream_redirected_ = true;
    }
  }
}

void GvspLossRelay::relay_stream_packet() {
  std::uint8_t packet[65536];
  const ssize_t n = recv(stream_fd_, packet, sizeof packet, 0);
  if (n <= 0) return;
  bool drop = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (n < kGvspHeaderBytes || (packet[4] & kGvspExtendedId) != 0) {
      ++unknown_packets_;
    } else {
      const std::uint16_t block_id = static_cast<std::uint16_t>((packet[2] << 8) | packet[3]);
      const std::uint32_t packet_id = read_be32(packet + 4) & 0x00FFFFFFu;
      if (frames_.empty() || frames_.back().block_id != block_id) frames_.push_back({block_id});
      drop = scripted_loss(static_cast<int>(frames_.size()) - 1, packet_id,
                           (packet[4] & 0x0F) == kGvspTrailer);
      ++(drop ? frames_.back().dropped : frames_.back().forwarded);
    }
  }
  if (drop || client_stream_.sin_family != AF_INET) return;
  sendto(stream_fd_, packet, static_cast<size_t>(n), 0,
         reinterpret_cast<const sockaddr*>(&client_stream_), sizeof client_stream_);
}

bool GvspLossRelay::scripted_loss(int frame, std::uint32_t packet, bool trailer) const {
  return std::any_of(losses_.begin(), losses_.end(), [&](const Loss& l) {
    return l.frame == frame && (l.packet == packet || (trailer && l.packet == kTrailer));
  });
}

}  // namespace vision_test
