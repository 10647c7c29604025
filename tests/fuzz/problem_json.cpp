// `rig solve`'s problem JSON: accepted, or refused with ProblemError.
#include "fuzz_input.hpp"
#include "solve_problem.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    (void)rig::cli::parse_problem(rig_fuzz::text(data, size), "/nonexistent");
  } catch (const rig::cli::ProblemError&) {
  }
  return 0;
}
