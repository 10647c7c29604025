#include "db/store/saved_frame.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

#include "db/store/sha256.hpp"

namespace db::store {

std::string read_saved_frame(const std::string& path, const std::string& sha256) {
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw SavedFrameError("cannot read recorded frame " + path + ": " + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw SavedFrameError("cannot read recorded frame " + path);
  std::string bytes = buffer.str();
  const std::string actual = sha256_hex(bytes);
  if (actual != sha256)
    throw SavedFrameError("recorded frame " + path + " has SHA-256 " + actual.substr(0, 12) +
                          "... but the run stored " + sha256.substr(0, 12) +
                          "...; the file changed since it was recorded");
  return bytes;
}

}  // namespace db::store
