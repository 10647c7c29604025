// The messages of protocol rig-estimator version 1 (docs/external-estimators.md):
// building rig's requests and checking an estimator's answers.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "rig/estimator/external_estimator.hpp"

namespace rig::estimator::protocol {

// rig's hello line (with '\n').
std::string hello_line();

// Checks an estimator's hello line. Returns the failure (kProtocol for
// another protocol or version, kMalformed for anything else that is not a
// hello) or nothing, filling name and version.
std::optional<Failure> check_hello(const std::string& line, std::string& name,
                                   std::string& version);

// rig's frame line (with '\n'); camera and target are camera_json() and
// target_json() text.
std::string frame_line(std::int64_t frame_id, const FrameRequest& request, int width_px,
                       int height_px, const std::string& camera, const std::string& target,
                       bool send_corners);

// Reads an estimator's answer to frame `frame_id` into `result` (poses,
// time, or a kDeclined / kMalformed failure).
void read_result(const std::string& line, std::int64_t frame_id, FrameResult& result);

}  // namespace rig::estimator::protocol
