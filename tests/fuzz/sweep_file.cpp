// A sweep file (TOML): accepted, or refused with a config::ConfigError
// (SweepConfigError, or the error of a file it names) or a PlanError.
#include "config/error.hpp"
#include "fuzz_input.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "vision/camera.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rig_fuzz::as_file(rig_fuzz::text(data, size), ".toml");
  try {
    (void)rig::sweep::load_sweep_config(path);
  } catch (const config::ConfigError&) {
  } catch (const rig::sweep::PlanError&) {
  } catch (const vision::CalibrationError&) {
  }
  return 0;
}
