// libmodbus calls behind ModbusLink (see modbus_link.hpp).
#include "motion/modbus_link.hpp"

#include <modbus/modbus.h>

#include <cerrno>

#include "motion/errors.hpp"

namespace motion {

ModbusLink::ModbusLink(const BenchUrl& url, int unit_id, std::chrono::milliseconds timeout)
    : url_(url) {
  if (url.transport == BenchUrl::Transport::kTcp) {
    // _pi: resolves host names as well as addresses.
    ctx_ = modbus_new_tcp_pi(url.host.c_str(), std::to_string(url.port).c_str());
  } else {
    ctx_ = modbus_new_rtu(url.device.c_str(), url.baud, url.parity, url.data_bits, url.stop_bits);
  }
  if (!ctx_) {
    throw ProfileError("bench URL " + url.str() +
                       ": libmodbus refused it: " + modbus_strerror(errno));
  }
  modbus_set_slave(ctx_, unit_id);
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(timeout).count();
  modbus_set_response_timeout(ctx_, static_cast<uint32_t>(us / 1000000),
                              static_cast<uint32_t>(us % 1000000));
  // The same bound on a gap inside a reply: libmodbus's own (500 ms) let a
  // drive that sent part of a frame hold every request for half a second,
  // whatever link.response_timeout_ms said.
  modbus_set_byte_timeout(ctx_, static_cast<uint32_t>(us / 1000000),
                          static_cast<uint32_t>(us % 1000000));
  // No libmodbus error recovery: a reconnect must be followed by a state
  // re-read, which only ModbusBench can do.
  modbus_set_error_recovery(ctx_, MODBUS_ERROR_RECOVERY_NONE);
}

ModbusLink::~ModbusLink() {
  close();
  modbus_free(ctx_);
}

int ModbusLink::connect() {
  close();
  if (modbus_connect(ctx_) == -1) return errno;
  connected_ = true;
  return 0;
}

void ModbusLink::close() {
  if (connected_) modbus_close(ctx_);
  connected_ = false;
}

int ModbusLink::finish(int rc) {
  if (rc != -1) return 0;
  const int err = errno;
  if (is_link_error(err)) close();
  return err;
}

int ModbusLink::read(RegisterTable table, int address, int count, std::uint16_t* out) {
  if (!connected_) return ENOTCONN;
  const int rc = table == RegisterTable::kInput
                     ? modbus_read_input_registers(ctx_, address, count, out)
                     : modbus_read_registers(ctx_, address, count, out);
  return finish(rc);
}

int ModbusLink::write(int address, int count, const std::uint16_t* values) {
  if (!connected_) return ENOTCONN;
  // Function 06 for one register, 16 for several: some drives accept only 06
  // on command registers.
  const int rc = count == 1 ? modbus_write_register(ctx_, address, values[0])
                            : modbus_write_registers(ctx_, address, count, values);
  return finish(rc);
}

bool ModbusLink::is_link_error(int err) {
  return !(err >= EMBXILFUN && err <= EMBXGTAR);
}

std::string ModbusLink::describe(int err) {
  return modbus_strerror(err);
}

}  // namespace motion
