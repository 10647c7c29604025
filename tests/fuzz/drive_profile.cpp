// A drive profile (TOML): accepted, or refused with motion::ProfileError
// (a config::ConfigError).
#include "motion/drive_profile.hpp"

#include "config/error.hpp"
#include "fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)motion::parse_drive_profile(rig_fuzz::text(data, size), "fuzz.toml");
  } catch (const config::ConfigError&) {
  }
  return 0;
}
