// The simulated bench's Modbus server (see sim/bench/server.hpp).
#include "sim/bench/server.hpp"

#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "motion/errors.hpp"

namespace sim::bench {
namespace {

using Clock = std::chrono::steady_clock;

// Registers a table must hold for the given fields: one past the highest.
int table_size(std::initializer_list<std::pair<int, int>> fields) {
  int n = 0;
  for (auto [first, count] : fields)
    n = std::max(n, first + count);
  return n;
}

}  // namespace

BenchServer::BenchServer(motion::DriveProfile profile, BenchSimConfig config,
                         BenchServerOptions options)
    : profile_(std::move(profile)),
      config_(std::move(config)),
      options_(std::move(options)),
      dynamics_(config_, profile_.home_x_mm, profile_.home_y_mm),
      faults_(config_.faults) {
  // The simulated drive keeps its command register and uses 32-bit positions
  // (docs/register-map.md); other conventions are emulated by the test drives.
  if (profile_.axis_drives) {
    throw motion::ProfileError(profile_.source +
                               ": the simulated bench is one controller of both axes; expected a "
                               "profile with [link] and [registers], not two drives in [x] and "
                               "[y] (tests/motion/axis_drives.py emulates those)");
  }
  if (profile_.position_bits != 32 ||
      profile_.protocol.handshake != motion::CommandHandshake::kKept ||
      profile_.protocol.servo_on != 0 || profile_.protocol.reset_pulse) {
    throw motion::ProfileError(profile_.source +
                               ": the simulated bench serves only 32-bit positions "
                               "(units.position_bits = 32) and a command register that keeps "
                               "its code (no [handshake] table)");
  }
  const motion::RegisterMap& r = profile_.registers;
  const std::initializer_list<std::pair<int, int>> writes = {
      {r.target_x, 2}, {r.target_y, 2}, {r.speed, 1}, {r.command, 1}};
  const std::initializer_list<std::pair<int, int>> feedback = {
      {r.actual_x, 2}, {r.actual_y, 2}, {r.status, 1}, {r.alarm, 1}};
  const bool in_holding = r.feedback == motion::RegisterTable::kHolding;
  const int holding = std::max(table_size(writes), in_holding ? table_size(feedback) : 0);
  const int input = in_holding ? 0 : table_size(feedback);
  mapping_ = modbus_mapping_new(0, 0, holding, input);
  if (!mapping_) throw std::runtime_error("sim bench: cannot allocate the register map");
}

BenchServer::~BenchServer() {
  stop();
  modbus_mapping_free(mapping_);
}

std::string BenchServer::url() const {
  if (!options_.rtu_device.empty()) {
    return "modbus-rtu://" + options_.rtu_device + "?baud=" + std::to_string(options_.rtu_baud) +
           "&parity=N&stop=1";
  }
  return "modbus-tcp://" + options_.host + ":" + std::to_string(port_);
}

void BenchServer::start() {
  if (physics_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    physics_stop_ = false;
  }
  physics_ = std::thread([this] { physics_loop(); });
  try {
    start_network();
  } catch (...) {
    stop();
    throw;
  }
}

void BenchServer::stop() {
  stop_network();
  if (physics_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      physics_stop_ = true;
    }
    physics_cv_.notify_all();
    physics_.join();
  }
}

void BenchServer::restart_network(std::chrono::milliseconds downtime) {
  stop_network();
  std::this_thread::sleep_for(downtime);
  start_network();
}

void BenchServer::power_cycle(std::chrono::milliseconds downtime) {
  stop_network();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    dynamics_.power_cycle();
  }
  std::this_thread::sleep_for(downtime);
  start_network();
}

void BenchServer::start_network() {
  if (network_.joinable()) return;
  const bool rtu = !options_.rtu_device.empty();
  if (rtu) {
    ctx_ = modbus_new_rtu(options_.rtu_device.c_str(), options_.rtu_baud, 'N', 8, 1);
    if (!ctx_ || modbus_set_slave(ctx_, profile_.unit_id) == -1 || modbus_connect(ctx_) == -1) {
      const std::string err = modbus_strerror(errno);
      if (ctx_) modbus_free(ctx_);
      ctx_ = nullptr;
      throw std::runtime_error("sim bench: cannot open " + options_.rtu_device + ": " + err);
    }
  } else {
    ctx_ = modbus_new_tcp(options_.host.c_str(), port_ != 0 ? port_ : options_.port);
    if (ctx_) listen_fd_ = modbus_tcp_listen(ctx_, options_.max_clients);
    if (!ctx_ || listen_fd_ == -1) {
      const int code = errno;
      const std::string err = modbus_strerror(code);
      if (ctx_) modbus_free(ctx_);
      ctx_ = nullptr;
      const std::string where =
          options_.host + ":" + std::to_string(port_ != 0 ? port_ : options_.port);
      throw std::runtime_error(
          "sim bench: cannot listen on " + where + ": " + err +
          (code == EADDRINUSE ? ": another rig sim (or rig sim bench) probably serves there; stop "
                                "it, or give this one another port ([bench] port of the "
                                "simulated rig file, --port of rig sim bench; 0 picks a free one)"
                              : std::string()));
    }
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
  }
  if (pipe(wake_) == -1)
    throw std::runtime_error("sim bench: pipe: " + std::string(strerror(errno)));
  {
    std::lock_guard<std::mutex> lock(mutex_);
    network_stop_ = false;
  }
  network_ = std::thread([this] { network_loop(); });
}

void BenchServer::stop_network() {
  if (!network_.joinable()) return;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    network_stop_ = true;
  }
  const char byte = 1;
  // Should the write fail, the loop still sees network_stop_ at its next
  // select timeout (100 ms).
  [[maybe_unused]] const ssize_t woken = write(wake_[1], &byte, 1);
  network_.join();
  if (listen_fd_ != -1) ::close(listen_fd_);
  listen_fd_ = -1;
  if (!options_.rtu_device.empty()) modbus_close(ctx_);
  modbus_free(ctx_);
  ctx_ = nullptr;
  ::close(wake_[0]);
  ::close(wake_[1]);
  wake_[0] = wake_[1] = -1;
}

void BenchServer::physics_loop() {
  std::unique_lock<std::mutex> lock(mutex_);
  auto last = Clock::now();
  while (!physics_stop_) {
    physics_cv_.wait_for(lock, std::chrono::milliseconds(1));
    const auto now = Clock::now();
    dynamics_.advance(std::chrono::duration<double>(now - last).count() * config_.time_scale);
    last = now;
  }
}

bool BenchServer::wait_wall(std::chrono::microseconds d) {
  pollfd p{wake_[0], POLLIN, 0};
  const int ms = static_cast<int>((d.count() + 999) / 1000);
  return poll(&p, 1, ms) == 0;
}

void BenchServer::network_loop() {
  const bool rtu = !options_.rtu_device.empty();
  const int serial_fd = rtu ? modbus_get_socket(ctx_) : -1;
  std::vector<int> clients;
  std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  for (;;) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (network_stop_) break;
    }
    fd_set rd;
    FD_ZERO(&rd);
    FD_SET(wake_[0], &rd);
    int max_fd = wake_[0];
    auto watch = [&](int fd) {
      FD_SET(fd, &rd);
      max_fd = std::max(max_fd, fd);
    };
    const auto now = Clock::now();
    const bool stalled = now < stall_until_;
    if (!stalled) {
      if (rtu) {
        watch(serial_fd);
      } else {
        watch(listen_fd_);
        for (int fd : clients)
          watch(fd);
      }
    }
    auto wait = std::chrono::microseconds(100000);
    if (stalled) {
      wait =
          std::min(wait, std::chrono::duration_cast<std::chrono::microseconds>(stall_until_ - now));
    }
    timeval tv{0, static_cast<suseconds_t>(wait.count())};
    const int n = select(max_fd + 1, &rd, nullptr, nullptr, &tv);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 || FD_ISSET(wake_[0], &rd)) break;
    if (n == 0 || stalled) continue;

    if (rtu) {
      const int rc = modbus_receive(ctx_, query);
      if (rc > 0) {
        handle(query, rc);
      } else if (rc == -1) {
        modbus_flush(ctx_);  // a garbled frame: drop what is left of it
      }
      continue;
    }
    const std::vector<int> ready = clients;
    if (FD_ISSET(listen_fd_, &rd)) {
      const int fd = accept(listen_fd_, nullptr, nullptr);
      if (fd >= 0 && static_cast<int>(clients.size()) >= options_.max_clients) {
        ::close(fd);
      } else if (fd >= 0) {
        const int one = 1;
        setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        clients.push_back(fd);
      }
    }
    for (int fd : ready) {
      if (!FD_ISSET(fd, &rd) || Clock::now() < stall_until_) continue;
      modbus_set_socket(ctx_, fd);
      const int rc = modbus_receive(ctx_, query);
      if (rc == -1 || (rc > 0 && !handle(query, rc))) {
        ::close(fd);
        clients.erase(std::find(clients.begin(), clients.end(), fd));
      }
    }
  }
  for (int fd : clients)
    ::close(fd);
}

bool BenchServer::handle(const std::uint8_t* query, int length) {
  const int h = modbus_get_header_length(ctx_);
  const int function = query[h];
  auto word = [&](int offset) { return (query[h + offset] << 8) | query[h + offset + 1]; };
  int first = -1, count = 0;
  if (function == MODBUS_FC_WRITE_SINGLE_REGISTER) {
    first = word(1), count = 1;
  } else if (function == MODBUS_FC_WRITE_MULTIPLE_REGISTERS) {
    first = word(1), count = word(3);
  } else if (function == MODBUS_FC_WRITE_AND_READ_REGISTERS) {
    first = word(5), count = word(7);
  }
  const bool is_write = first >= 0;

  bool drop = false, refuse = false, ignore = false;
  double stall_s = 0, delay_ms = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ++requests_;
    if (faults_.drop_after_requests > 0) drop = --faults_.drop_after_requests == 0;
    if (faults_.stall_after_requests > 0 && --faults_.stall_after_requests == 0) {
      stall_s = faults_.stall_s;
    }
    delay_ms = faults_.reply_delay_ms;
    if (faults_.late_after_requests > 0 && --faults_.late_after_requests == 0) {
      delay_ms += faults_.late_ms;
    }
    if (is_write && faults_.refuse_writes > 0) {
      --faults_.refuse_writes;
      refuse = true;
    } else if (is_write && faults_.ignore_writes > 0) {
      --faults_.ignore_writes;
      ignore = true;
    }
  }
  if (drop) return false;
  if (stall_s > 0) {
    stall_until_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(stall_s));
    return true;
  }
  if (delay_ms > 0 &&
      !wait_wall(std::chrono::microseconds(static_cast<std::int64_t>(delay_ms * 1000)))) {
    return false;
  }
  if (refuse) {
    modbus_reply_exception(ctx_, query, MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE);
    return true;
  }

  std::lock_guard<std::mutex> lock(mutex_);
  refresh_feedback();
  const bool in_range = is_write && first + count <= mapping_->nb_registers;
  std::vector<std::uint16_t> saved;
  if (ignore)
    saved.assign(mapping_->tab_registers, mapping_->tab_registers + mapping_->nb_registers);
  if (modbus_reply(ctx_, query, length, mapping_) == -1) return false;
  if (ignore) {
    std::copy(saved.begin(), saved.end(), mapping_->tab_registers);
  } else if (in_range) {
    apply_write(first, count);
  }
  return true;
}

void BenchServer::refresh_feedback() {
  const motion::RegisterMap& r = profile_.registers;
  const motion::WordOrder order = profile_.word_order;
  if (dynamics_.take_homing_completed()) {
    motion::encode_int32(profile_.to_counts(profile_.home_x_mm), order,
                         mapping_->tab_registers + r.target_x);
    motion::encode_int32(profile_.to_counts(profile_.home_y_mm), order,
                         mapping_->tab_registers + r.target_y);
  }
  std::uint16_t* table = r.feedback == motion::RegisterTable::kInput ? mapping_->tab_input_registers
                                                                     : mapping_->tab_registers;
  motion::encode_int32(profile_.to_counts(dynamics_.encoder_x_mm()), order, table + r.actual_x);
  motion::encode_int32(profile_.to_counts(dynamics_.encoder_y_mm()), order, table + r.actual_y);
  const motion::StatusBits& b = profile_.status_bits;
  auto bit = [](bool on, int n) { return static_cast<std::uint16_t>(on ? 1u << n : 0u); };
  table[r.status] = bit(dynamics_.homed(), b.homed) | bit(dynamics_.moving(), b.moving) |
                    bit(dynamics_.in_position(), b.in_position) | bit(dynamics_.alarm(), b.alarm) |
                    bit(dynamics_.emergency_stop(), b.emergency_stop);
  table[r.alarm] = static_cast<std::uint16_t>(dynamics_.alarm_code());
}

void BenchServer::apply_write(int first, int count) {
  const motion::RegisterMap& r = profile_.registers;
  const std::uint16_t* regs = mapping_->tab_registers;
  auto touches = [&](int address, int n) { return first < address + n && address < first + count; };
  const double x_mm = profile_.to_mm(motion::decode_int32(regs + r.target_x, profile_.word_order));
  const double y_mm = profile_.to_mm(motion::decode_int32(regs + r.target_y, profile_.word_order));
  if (touches(r.target_x, 2) || touches(r.target_y, 2)) {
    WrittenTarget w;
    if (touches(r.target_x, 2)) w.x_mm = x_mm;
    if (touches(r.target_y, 2)) w.y_mm = y_mm;
    written_.push_back(w);
  }
  if (!touches(r.command, 1)) return;
  const std::uint16_t code = regs[r.command];
  const motion::CommandCodes& c = profile_.commands;
  if (code == c.move_absolute) {
    dynamics_.move(x_mm, y_mm, regs[r.speed] / profile_.speed_units_per_mm_s);
  } else if (code == c.home) {
    dynamics_.home();
  } else if (code == c.stop) {
    dynamics_.stop();
  } else if (code == c.reset_alarm) {
    dynamics_.reset_alarm();
  } else if (code != 0) {  // 0: idle, as on most drives
    dynamics_.raise_alarm(kAlarmBadCommand);
  }
}

motion::XY BenchServer::actual_position_mm() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {dynamics_.actual_x_mm(), dynamics_.actual_y_mm()};
}

motion::XY BenchServer::encoder_position_mm() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return {dynamics_.encoder_x_mm(), dynamics_.encoder_y_mm()};
}

std::vector<BenchServer::WrittenTarget> BenchServer::written_targets() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return written_;
}

std::uint64_t BenchServer::requests() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return requests_;
}

void BenchServer::inject(const FaultPlan& faults) {
  std::lock_guard<std::mutex> lock(mutex_);
  faults_ = faults;
  dynamics_.arm_alarm_at(faults.alarm_at);
}

void BenchServer::set_emergency_stop(bool on) {
  std::lock_guard<std::mutex> lock(mutex_);
  dynamics_.set_emergency_stop(on);
}

}  // namespace sim::bench
