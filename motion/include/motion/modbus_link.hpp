// motion::ModbusLink: one libmodbus context (TCP or RTU) with the calls
// ModbusBench needs, and a classification of what went wrong. It does not
// retry: the reconnect watchdog lives one level up, in ModbusBench, because
// only the bench knows which state to re-read after a reconnect.
//
// Links to units on one serial device (two drives on one RS-485 line) share
// one open port, one libmodbus context and one record of the last frame, so
// that the silent interval is kept between frames to different units too;
// each request addresses its own link's unit. Closing the port (after a link
// error) closes it for every link on it; the next request of each reopens it.
//
// Not thread-safe: one link, one thread (the links sharing a line included).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "motion/bench_url.hpp"
#include "motion/drive_profile.hpp"

typedef struct _modbus modbus_t;

namespace motion {

class ModbusLink {
 public:
  // Creates the context, or for RTU joins the line another link holds open on
  // the same device; does not connect. Throws ProfileError if libmodbus
  // refuses the parameters (e.g. an unsupported baud rate), or if the device
  // is in use by another link at other serial settings.
  ModbusLink(const BenchUrl& url, int unit_id, std::chrono::milliseconds response_timeout);
  ~ModbusLink();
  ModbusLink(const ModbusLink&) = delete;
  ModbusLink& operator=(const ModbusLink&) = delete;

  // One attempt. Returns 0, or the errno of the failure.
  int connect();
  // Closes the socket or serial port (idempotent). A closed link must be
  // connect()ed again; libmodbus never does it behind our back.
  void close();
  bool connected() const;

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

  // RTU: the silent interval that must separate two frames on the line, 3.5
  // character times at the URL's baud rate, parity and stop bits (a
  // character is 1 start, data, parity and stop bits), and 1750 us above
  // 19200 baud ("MODBUS over serial line specification and implementation
  // guide V1.02", section 2.5.1.1). Every request is sent at least this long
  // after the end of the last frame the link saw (the answer, or a request
  // that went unanswered). Zero for TCP.
  static std::chrono::microseconds frame_silence(const BenchUrl& url);

  // RTU, after a read or write failed with EMBBADSLAVE: the unit id that
  // answered instead of the one asked, when a second request showed it.
  std::optional<int> foreign_unit() const { return foreign_unit_; }
  int unit_id() const { return unit_id_; }

 private:
  struct Line;
  int finish(int rc);
  // Addresses this link's unit with its timeout on the (possibly shared) context.
  void select();
  // Sleeps until frame_silence() has passed since the last frame ended, then
  // (RTU) drops whatever the line received since: no answer to the request
  // about to be sent.
  void keep_silence();
  // RTU, after a request failed on the link (no answer in time, a garbled or
  // a wrong answer): waits one response timeout for the reply that may still
  // be on its way and drops it, so that it is not read as the answer to the
  // next request. Nothing for TCP, where a reconnect opens a new connection.
  void drop_late_reply();
  // Asks the unit once more with a raw request and returns the unit id the
  // answer carries, if it is another one (libmodbus reports only that it
  // differs).
  std::optional<int> probe_answering_unit();

  BenchUrl url_;
  int unit_id_;
  std::chrono::microseconds timeout_;
  std::shared_ptr<Line> line_;
  std::chrono::microseconds silence_{0};
  std::optional<int> foreign_unit_;
};

}  // namespace motion
