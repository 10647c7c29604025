// A camera calibration file (OpenCV YAML/XML, ROS YAML): accepted, or
// refused with vision::CalibrationError. The first byte picks the extension,
// so both of OpenCV's parsers are reached.
#include "fuzz_input.hpp"
#include "vision/camera.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::string path =
      rig_fuzz::as_file(rig_fuzz::text(data + 1, size - 1), data[0] & 1 ? ".xml" : ".yaml");
  try {
    (void)vision::Camera::load(path);
  } catch (const vision::CalibrationError&) {
  }
  return 0;
}
