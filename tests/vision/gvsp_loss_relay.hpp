// A lossy network between a GigE Vision client and a camera on loopback that
// loses exactly the stream packets a script names, so that a test of
// incomplete frames is deterministic.
//
// The relay answers GigE Vision control (GVCP, UDP 3956) at its own address
// and forwards every command to the camera and every answer back, unchanged
// except for the client's writes of the stream destination (bootstrap
// registers SCDA0 0x0D18 and SCP0 0x0D00 of the GigE Vision standard): those are
// pointed at the relay's stream socket, which forwards the camera's stream
// (GVSP) packets to the client's real destination, dropping the scripted
// ones. Nothing else is dropped, reordered or delayed on purpose.
//
// Frames are counted in the order the camera sends them (a new GVSP block id
// starts a frame), from 0; packets by their GVSP packet id (0 the leader,
// 1.. the data, the last one the trailer). Only standard (16-bit block id)
// GVSP headers are understood; an extended-id packet is forwarded and
// counted in unknown_packets().
//
// Threads: one relay thread, started by the constructor and joined by the
// destructor; the accessors may be called from any thread.
#pragma once

#include <netinet/in.h>

#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace vision_test {

class GvspLossRelay {
 public:
  // Loss::packet of a frame's trailer, whatever its packet id.
  static constexpr std::uint32_t kTrailer = 0xFFFFFFFFu;
  struct Loss {
    int frame;             // 0 = the first frame the camera sends through the relay
    std::uint32_t packet;  // GVSP packet id within that frame (0 the leader), or kTrailer
  };
  // What went through, per frame, in sending order.
  struct FrameTally {
    std::uint16_t block_id = 0;  // the camera's frame id
    int forwarded = 0;           // packets passed on to the client
    int dropped = 0;             // packets lost as scripted
  };

  // Listens for control at relay_address:3956 and relays to the camera at
  // camera_address:3956 (both IPv4 loopback addresses). Throws
  // std::runtime_error naming the address when a socket cannot be bound.
  GvspLossRelay(const std::string& camera_address, const std::string& relay_address,
                std::vector<Loss> losses);
  ~GvspLossRelay();
  GvspLossRelay(const GvspLossRelay&) = delete;
  GvspLossRelay& operator=(const GvspLossRelay&) = delete;

  // Whether the client's stream destination was seen and redirected.
  bool stream_redirected() const;
  std::vector<FrameTally> frames() const;
  int unknown_packets() const;

 private:
  void run();
  void relay_control_from_client();
  void relay_control_from_camera();
  void relay_stream_packet();
  void redirect_stream_destination(std::uint8_t* packet, long size);
  bool scripted_loss(int frame, std::uint32_t packet, bool trailer) const;

  std::vector<Loss> losses_;
  sockaddr_in camera_control_{};  // camera_address:3956
  sockaddr_in client_control_{};  // where the client's control commands came from
  sockaddr_in client_stream_{};   // the client's stream destination
  int control_fd_ = -1;           // relay_address:3956, faces the client
  int upstream_fd_ = -1;          // ephemeral, faces the camera's control port
  int stream_fd_ = -1;            // ephemeral, receives the camera's stream
  int wake_[2] = {-1, -1};        // written by the destructor to end the thread

  mutable std::mutex mutex_;  // guards the three below
  bool stream_redirected_ = false;
  std::vector<FrameTally> frames_;
  int unknown_packets_ = 0;

  std::thread thread_;
};

}  // namespace vision_test
