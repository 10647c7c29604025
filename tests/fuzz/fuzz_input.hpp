// What every fuzz target shares: the rule that an input is either accepted
// or refused with one of the parser's documented error types. Anything else
// escaping (a std::bad_alloc, a nlohmann type_error, a crash, a sanitizer
// report) is a finding: libFuzzer stops and writes the input.
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>

namespace rig_fuzz {

inline std::string text(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// Writes the input to a file of this process (for parsers that read a
// path) and returns its path; `extension` selects the format where the
// parser looks at it.
inline std::string as_file(const std::string& bytes, const std::string& extension) {
  const std::string path = "/tmp/rig-fuzz-" + std::to_string(::getpid()) + extension;
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
  return path;
}

}  // namespace rig_fuzz
