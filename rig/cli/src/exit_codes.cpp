#include "exit_codes.hpp"

#include <exception>
#include <iostream>

#include "config/error.hpp"
#include "config/json.hpp"
#include "db/report/report.hpp"
#include "db/store/store.hpp"
#include "motion/errors.hpp"
#include "rig/calibrate/calibration.hpp"
#include "rig/sweep/run_record.hpp"
#include "rig/sweep/sweep_config.hpp"
#include "rig/sweep/sweep_plan.hpp"
#include "rig/telemetry/telemetry.hpp"
#include "vision/artwork.hpp"
#include "vision/camera.hpp"
#include "vision/correspondences.hpp"
#include "vision/detector_image.hpp"
#include "vision/frame_source.hpp"
#include "vision/target.hpp"

namespace rig::cli {
namespace {

// How rig reports one type of error.
struct ErrorKind {
  bool (*is)(const std::exception&);
  int code;
  const char* subject;  // the part of the rig that failed, or "" when the message says it
};

template <class Error>
bool is(const std::exception& e) {
  return dynamic_cast<const Error*>(&e) != nullptr;
}

// Every error type rig maps, the more derived before its base: the first row
// an exception is an instance of decides.
const ErrorKind kErrorKinds[] = {
    // Bad input: the message names the file, key or option and the value.
    {is<BadInput>, kExitBadInput, ""},
    {is<sweep::SweepConfigError>, kExitBadInput, ""},
    {is<sweep::PlanError>, kExitBadInput, ""},
    {is<sweep::RunMismatch>, kExitBadInput, ""},
    {is<calibrate::CalibrationInputError>, kExitBadInput, ""},  // also an unobservable plan
    {is<config::ConfigError>, kExitBadInput, ""},  // every config file: sweep, profile, target, rig
    {is<config::JsonInputError>, kExitBadInput, ""},  // JSON too big, too deep or malformed
    {is<vision::CalibrationError>, kExitBadInput, ""},
    {is<vision::TargetError>, kExitBadInput, ""},
    {is<vision::ImageError>, kExitBadInput, ""},
    {is<vision::InputError>, kExitBadInput, ""},
    {is<motion::ProfileError>, kExitBadInput, ""},
    {is<motion::SoftLimitError>, kExitBadInput, ""},
    {is<db::report::ReportInputError>, kExitBadInput, ""},
    {is<db::store::SchemaError>, kExitBadInput, "database"},
    {is<telemetry::EndpointError>, kExitBadInput, "telemetry"},
    // Failures while running.
    {is<telemetry::TelemetryError>, kExitFailure, "telemetry"},  // e.g. a port another sweep holds
    {is<vision::CaptureError>, kExitFailure, "camera"},
    {is<motion::BenchError>, kExitFailure, "bench"},
    {is<db::store::StoreError>, kExitFailure, "database"},
    {is<vision::ArtworkError>, kExitFailure, ""},  // a file that cannot be written
};

}  // namespace

int run_command(const std::string& command, const std::function<int()>& body) {
  try {
    return body();
  } catch (const std::exception& e) {
    int code = kExitFailure;
    std::string subject;
    for (const ErrorKind& kind : kErrorKinds) {
      if (!kind.is(e)) continue;
      code = kind.code;
      subject = kind.subject;
      break;
    }
    std::cerr << "rig " << command << ": "
              << (subject.empty() || subject == command ? "" : subject + ": ") << e.what() << "\n";
    return code;
  }
}

void read_input(const std::string& input, const std::function<void()>& read) {
  try {
    read();
  } catch (const std::exception& e) {
    throw BadInput(input.empty() ? e.what() : input + ": " + e.what());
  }
}

}  // namespace rig::cli
