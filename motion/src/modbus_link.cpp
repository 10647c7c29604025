// libmodbus calls behind ModbusLink (see modbus_link.hpp).
#include "motion/modbus_link.hpp"

#include <modbus/modbus.h>

#include <cerrno>
#include <map>
#include <thread>

#include "motion/errors.hpp"

namespace motion {

std::chrono::microseconds ModbusLink::frame_silence(const BenchUrl& url) {
  if (url.transport != BenchUrl::Transport::kRtu) return std::chrono::microseconds(0);
  if (url.baud > 19200) return std::chrono::microseconds(1750);
  const int char_bits = 1 + url.data_bits + (url.parity == 'N' ? 0 : 1) + url.stop_bits;
  // 3.5 characters of char_bits bits at `baud` bits per second, rounded up.
  const long long us = (35LL * char_bits * 1000000 + 10LL * url.baud - 1) / (10LL * url.baud);
  return std::chrono::microseconds(us);
}

// One open port (or socket) and what the silent interval needs to know of it.
struct ModbusLink::Line {
  modbus_t* ctx = nullptr;
  bool connected = false;
  std::chrono::steady_clock::time_point last_frame_end{};
  BenchUrl settings;
  ~Line() {
    if (connected) modbus_close(ctx);
    modbus_free(ctx);
  }
};

namespace {

// The RTU lines open in this process, by device.
std::map<std::string, std::weak_ptr<void>>& rtu_lines() {
  static std::map<std::string, std::weak_ptr<void>> lines;
  return lines;
}

bool same_serial_settings(const BenchUrl& a, const BenchUrl& b) {
  return a.baud == b.baud && a.parity == b.parity && a.data_bits == b.data_bits &&
         a.stop_bits == b.stop_bits;
}

}  // namespace

ModbusLink::ModbusLink(const BenchUrl& url, int unit_id, std::chrono::milliseconds timeout)
    : url_(url),
      unit_id_(unit_id),
      timeout_(std::chrono::duration_cast<std::chrono::microseconds>(timeout)),
      silence_(frame_silence(url)) {
  const bool rtu = url.transport == BenchUrl::Transport::kRtu;
  if (rtu) {
    if (auto shared = std::static_pointer_cast<Line>(rtu_lines()[url.device].lock())) {
      if (!same_serial_settings(shared->settings, url)) {
        throw ProfileError("bench URL " + url.str() + ": " + url.device +
                           " is already in use at other serial settings (" +
                           shared->settings.str() +
                           "); expected the same baud, parity, data and stop bits for every "
                           "drive on one line");
      }
      line_ = shared;
      return;
    }
  }
  line_ = std::make_shared<Line>();
  line_->settings = url;
  // _pi: resolves host names as well as addresses.
  line_->ctx =
      rtu ? modbus_new_rtu(url.device.c_str(), url.baud, url.parity, url.data_bits, url.stop_bits)
          : modbus_new_tcp_pi(url.host.c_str(), std::to_string(url.port).c_str());
  if (!line_->ctx) {
    throw ProfileError("bench URL " + url.str() +
                       ": libmodbus refused it: " + modbus_strerror(errno));
  }
  // No libmodbus error recovery: a reconnect must be followed by a state
  // re-read, which only ModbusBench can do.
  modbus_set_error_recovery(line_->ctx, MODBUS_ERROR_RECOVERY_NONE);
  if (rtu) rtu_lines()[url.device] = line_;
  select();
}

void ModbusLink::select() {
  modbus_t* ctx = line_->ctx;
  modbus_set_slave(ctx, unit_id_);
  const auto us = timeout_.count();
  modbus_set_response_timeout(ctx, static_cast<uint32_t>(us / 1000000),
                              static_cast<uint32_t>(us % 1000000));
  // The same bound on a gap inside a reply: libmodbus's own (500 ms) let a
  // drive that sent part of a frame hold every request for half a second,
  // whatever link.response_timeout_ms said.
  modbus_set_byte_timeout(ctx, static_cast<uint32_t>(us / 1000000),
                          static_cast<uint32_t>(us % 1000000));
}

// The line closes with its last link (Line's destructor).
ModbusLink::~ModbusLink() = default;

bool ModbusLink::connected() const {
  return line_->connected;
}

int ModbusLink::connect() {
  close();
  if (modbus_connect(line_->ctx) == -1) return errno;
  line_->connected = true;
  // A line just opened may carry the end of a frame: a silent interval first.
  line_->last_frame_end = std::chrono::steady_clock::now();
  return 0;
}

void ModbusLink::close() {
  if (line_->connected) modbus_close(line_->ctx);
  line_->connected = false;
}

void ModbusLink::keep_silence() {
  select();
  if (silence_.count() == 0) return;
  const auto ready = line_->last_frame_end + silence_;
  if (std::chrono::steady_clock::now() < ready) std::this_thread::sleep_until(ready);
  // Nothing received before a request is its answer: drop it (the end of a
  // reply the last request gave up on), for RTU has no transaction id that
  // would tell an old reply from the new one.
  modbus_flush(line_->ctx);
}

void ModbusLink::drop_late_reply() {
  if (silence_.count() == 0) return;
  std::this_thread::sleep_for(timeout_);
  modbus_flush(line_->ctx);
}

std::optional<int> ModbusLink::probe_answering_unit() {
  // Read holding register 0 (function 03): any answer carries its unit id.
  const std::uint8_t request[] = {static_cast<std::uint8_t>(unit_id_), 0x03, 0, 0, 0, 1};
  keep_silence();
  std::optional<int> unit;
  if (modbus_send_raw_request(line_->ctx, request, sizeof request) != -1) {
    std::uint8_t answer[MODBUS_RTU_MAX_ADU_LENGTH] = {};
    // libmodbus reads the whole frame, then refuses it for its unit id
    // (return 0 or -1); the frame's first byte is the unit that answered.
    modbus_receive_confirmation(line_->ctx, answer);
    if (answer[0] != 0 && answer[0] != unit_id_) unit = answer[0];
  }
  line_->last_frame_end = std::chrono::steady_clock::now();
  return unit;
}

int ModbusLink::finish(int rc) {
  line_->last_frame_end = std::chrono::steady_clock::now();
  if (rc != -1) return 0;
  const int err = errno;
  if (err == EMBBADSLAVE && url_.transport == BenchUrl::Transport::kRtu) {
    foreign_unit_ = probe_answering_unit();
  }
  if (is_link_error(err)) {
    drop_late_reply();
    close();
  }
  return err;
}

int ModbusLink::read(RegisterTable table, int address, int count, std::uint16_t* out) {
  if (!connected()) return ENOTCONN;
  keep_silence();
  modbus_t* ctx = line_->ctx;
  const int rc = table == RegisterTable::kInput
                     ? modbus_read_input_registers(ctx, address, count, out)
                     : modbus_read_registers(ctx, address, count, out);
  return finish(rc);
}

int ModbusLink::write(int address, int count, const std::uint16_t* values) {
  if (!connected()) return ENOTCONN;
  // Function 06 for one register, 16 for several: some drives accept only 06
  // on command registers.
  keep_silence();
  modbus_t* ctx = line_->ctx;
  const int rc = count == 1 ? modbus_write_register(ctx, address, values[0])
                            : modbus_write_registers(ctx, address, count, values);
  return finish(rc);
}

bool ModbusLink::is_link_error(int err) {
  return !(err >= EMBXILFUN && err <= EMBXGTAR);
}

std::string ModbusLink::describe(int err) {
  return modbus_strerror(err);
}

}  // namespace motion
