// motion::ModbusLink: one libmodbus context (TCP or RTU) with the calls
// ModbusBench needs, and a classification of what went wrong. It does not
// retry: the reconnect watchdog lives one level up, in ModbusBench, because
// only the bench knows which state to re-read after a reconnect.
//
// Not thread-safe: one link, one thread.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"

typedef struct _modbus modbus_t;

namespace motion {

class ModbusLink {
 public:
  // Creates the context; does not connect. Throws ProfileError if libmodbus
  // refuses the parameters (e.g. an unsupported baud rate).
  ModbusLink(const BenchUrl& url, int unit_id, std::chrono::milliseconds response_timeout);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  // One attempt. Returns 0, or the errno of the failure.
  int connect();
  // Closes the socket or serial port (idempotent). A closed link must be
  // connect()ed again; libmodbus never does it behind our back.
  void close();
  bool connected() const { return connected_; }

  // Each returns 0 on success, or the errno (ETIMEDOUT, ECONNRESET, EPIPE,
  // EMBX* for a Modbus exception response, ...). A link error (see
  // is_link_error) closes the link.
  int read(RegisterTable table, int address, int count, std::uint16_t* out);
  int write(int address, int count, const std::uint16_t* values);

  // True for errors of the link (socket, timeout, garbled frame), after which
  // the only safe course is to reconnect; false for a Modbus exception
  // response, which is the drive's considered answer.
  static bool is_link_error(int err);
  static std::string describe(int err);

  const BenchUrl& url() const { return url_; }

 private:
  int finish(int rc);

  BenchUrl url_;
  modbus_t* ctx_ = nullptr;
  bool connected_ = false;
};

}  // namespace motion
