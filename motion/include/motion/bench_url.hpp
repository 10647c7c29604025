// Where a bench is reached: a Modbus TCP host and port, or an RTU serial line.
//   modbus-tcp://HOST:PORT[?unit=N]
//   modbus-rtu:///dev/ttyUSB0?baud=115200&parity=N&data=8&stop=1&unit=1
// baud defaults to 19200, parity to E (the Modbus RTU default), data to 8,
// stop to 1 (2 when parity is N, as the Modbus serial spec asks, unless given).
// unit, when given, overrides the profile's link.unit_id.
#pragma once

#include <optional>
#include <string>

namespace motion {

struct BenchUrl {
  enum class Transport { kTcp, kRtu };
  Transport transport = Transport::kTcp;
  std::string host;    // TCP
  int port = 502;      // TCP
  std::string device;  // RTU, e.g. /dev/ttyUSB0
  int baud = 19200;
  char parity = 'E';  // 'N', 'E' or 'O'
  int data_bits = 8;
  int stop_bits = 1;
  std::optional<int> unit;

  // Parses a URL as above. Throws ProfileError naming the URL and the part
  // that is wrong (scheme, port, query key or value).
  static BenchUrl parse(const std::string& url);
  std::string str() const;
};

}  // namespace motion
