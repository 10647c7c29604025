// A control request as the sweep's REP socket receives it: every input gets
// a reply ({"ok": ...}) that can be serialised, and nothing throws.
#include <cstdlib>

#include "fuzz_input.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "telemetry_internal.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  rig::telemetry::ControlState state;
  const nlohmann::json reply =
      rig::telemetry::detail::answer_control_request(rig_fuzz::text(data, size), 1, state, [] {
        return nlohmann::json{{"state", "running"}};
      });
  if (!reply.is_object() || !reply.contains("ok")) std::abort();
  (void)reply.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return 0;
}
