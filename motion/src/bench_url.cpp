// Parsing of bench URLs (see bench_url.hpp).
#include "motion/bench_url.hpp"

#include <cstdlib>
#include <sstream>

#include "motion/errors.hpp"

namespace motion {
namespace {

int parse_int(const std::string& url, const std::string& what, const std::string& text, int min,
              int max) {
  char* end = nullptr;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || v < min || v > max) {
    throw ProfileError("bench URL " + url + ": " + what + " \"" + text +
                       "\" is not an integer in " + std::to_string(min) + ".." +
                       std::to_string(max));
  }
  return static_cast<int>(v);
}

}  // namespace

BenchUrl BenchUrl::parse(const std::string& url) {
  static const std::string kTcp = "modbus-tcp://";
  static const std::string kRtu = "modbus-rtu://";
  BenchUrl u;
  std::string rest;
  if (url.rfind(kTcp, 0) == 0) {
    u.transport = Transport::kTcp;
    rest = url.substr(kTcp.size());
  } else if (url.rfind(kRtu, 0) == 0) {
    u.transport = Transport::kRtu;
    rest = url.substr(kRtu.size());
  } else {
    throw ProfileError("bench URL " + url +
                       ": expected modbus-tcp://HOST:PORT or modbus-rtu:///dev/DEVICE?baud=...");
  }
  std::string query;
  if (auto q = rest.find('?'); q != std::string::npos) {
    query = rest.substr(q + 1);
    rest = rest.substr(0, q);
  }

  bool stop_given = false;
  std::istringstream items(query);
  for (std::string item; std::getline(items, item, '&');) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) {
      throw ProfileError("bench URL " + url + ": query item \"" + item + "\" is not key=value");
    }
    const std::string key = item.substr(0, eq);
    const std::string value = item.substr(eq + 1);
    if (key == "unit") {
      u.unit = parse_int(url, "unit", value, 1, 255);
    } else if (u.transport == Transport::kRtu && key == "baud") {
      u.baud = parse_int(url, "baud", value, 50, 4000000);
    } else if (u.transport == Transport::kRtu && key == "parity") {
      if (value != "N" && value != "E" && value != "O") {
        throw ProfileError("bench URL " + url + ": parity \"" + value + "\" is not N, E or O");
      }
      u.parity = value[0];
    } else if (u.transport == Transport::kRtu && key == "data") {
      u.data_bits = parse_int(url, "data", value, 5, 8);
    } else if (u.transport == Transport::kRtu && key == "stop") {
      u.stop_bits = parse_int(url, "stop", value, 1, 2);
      stop_given = true;
    } else {
      throw ProfileError("bench URL " + url + ": unknown query key \"" + key + "\"");
    }
  }

  if (u.transport == Transport::kTcp) {
    const auto colon = rest.rfind(':');
    if (colon == std::string::npos || colon == 0) {
      throw ProfileError("bench URL " + url + ": expected HOST:PORT after modbus-tcp://");
    }
    u.host = rest.substr(0, colon);
    u.port = parse_int(url, "port", rest.substr(colon + 1), 1, 65535);
  } else {
    if (rest.empty() || rest[0] != '/') {
      throw ProfileError("bench URL " + url +
                         ": expected an absolute device path, e.g. "
                         "modbus-rtu:///dev/ttyUSB0");
    }
    u.device = rest;
    if (!stop_given && u.parity == 'N') u.stop_bits = 2;
  }
  return u;
}

std::string BenchUrl::str() const {
  std::ostringstream s;
  if (transport == Transport::kTcp) {
    s << "modbus-tcp://" << host << ":" << port;
    if (unit) s << "?unit=" << *unit;
  } else {
    s << "modbus-rtu://" << device << "?baud=" << baud << "&parity=" << parity
      << "&data=" << data_bits << "&stop=" << stop_bits;
    if (unit) s << "&unit=" << *unit;
  }
  return s.str();
}

}  // namespace motion
