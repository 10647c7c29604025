// A CSV plan: accepted, or refused with rig::sweep::PlanError.
#include "fuzz_input.hpp"
#include "rig/sweep/sweep_plan.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = rig_fuzz::as_file(rig_fuzz::text(data, size), ".csv");
  try {
    (void)rig::sweep::SweepPlan::from_csv(path);
  } catch (const rig::sweep::PlanError&) {
  }
  return 0;
}
