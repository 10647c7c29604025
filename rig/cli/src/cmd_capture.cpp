// rig capture: saves N frames from a camera (or a replay) as PNG files, for a
// person checking a camera: is it reachable, triggered, exposed right, whole?
// Prints one line per frame and a summary with the source's counters.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <stdexcept>
#include <string>

#include "commands.hpp"
#include "vision/frame_source.hpp"
#include "vision/image_codecs.hpp"

namespace rig::cli {
namespace {

struct CaptureArgs {
  std::string camera;
  int frames = 1;
  std::string out;
  std::string trigger = "software";
  int timeout_ms = 2000;
  vision::CaptureOptions options;
};

std::string frame_file(int index) {
  char name[32];
  std::snprintf(name, sizeof name, "frame_%06d.png", index);
  return name;
}

// Opens the source and saves args.frames frames; returns how many were
// saved. A failure ends it, printed, so that the summary can still say what
// was saved and what the source counted.
int save_frames(const CaptureArgs& args, vision::FrameSource& source) {
  int saved = 0;
  try {
    source.open();
    for (int i = 0; i < args.frames; ++i) {
      const auto t0 = std::chrono::steady_clock::now();
      source.trigger();
      const vision::Frame frame = source.grab(std::chrono::milliseconds(args.timeout_ms));
      const double ms =
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      const std::string path = (std::filesystem::path(args.out) / frame_file(i)).string();
      if (!vision::imwrite(path, frame.image)) throw std::runtime_error("cannot write " + path);
      ++saved;
      std::cout << path << "  " << frame.image.cols << "x" << frame.image.rows << "  id "
                << frame.frame_id << "  camera_ts_ns " << frame.camera_timestamp_ns << "  " << ms
                << " ms\n";
    }
  } catch (const vision::EndOfFrames& e) {  // a replay folder that ran out, told with the summary
    std::cout << "rig capture: " << e.what() << "\n";
  } catch (const std::exception& e) {
    std::cerr << "rig capture: " << e.what() << "\n";
  }
  return saved;
}

int run_capture(CaptureArgs& args) {
  args.options.software_trigger = args.trigger == "software";
  std::unique_ptr<vision::FrameSource> source;
  read_input("", [&] {
    source = vision::make_frame_source(args.camera, args.options);
    std::filesystem::create_directories(args.out);
  });
  const auto start = std::chrono::steady_clock::now();
  const int saved = save_frames(args, *source);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const vision::CaptureCounters c = source->counters();
  std::cout << "rig capture: " << saved << "/" << args.frames << " frames saved to " << args.out
            << " in " << seconds << " s; incomplete " << c.incomplete << ", lost " << c.lost
            << ", timeouts " << c.timeouts << ", retries " << c.retries << ", discarded "
            << c.discarded << std::endl;
  source->close();
  return saved == args.frames ? kExitOk : kExitFailure;
}

}  // namespace

void add_capture_command(CLI::App& app, ExitStatus& status) {
  auto args = std::make_shared<CaptureArgs>();
  CLI::App* cmd = app.add_subcommand("capture", "Save frames from a camera, to check it");
  cmd->add_option("--camera", args->camera,
                  "gige:ID | gige:ADDRESS | v4l2:/dev/videoN | replay:DIR")
      ->required();
  cmd->add_option("--frames", args->frames, "Frames to save")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", args->out, "Folder for frame_NNNNNN.png (created)")->required();
  cmd->add_option("--trigger", args->trigger,
                  "software: one exposure per frame; free: the camera's own frame rate")
      ->capture_default_str()
      ->check(CLI::IsMember({"software", "free"}));
  cmd->add_option("--timeout-ms", args->timeout_ms, "Longest wait for one frame")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--pixel-format", args->options.pixel_format, "GenICam pixel format")
      ->capture_default_str();
  cmd->add_option("--width", args->options.width, "Region width, px (default: camera's)");
  cmd->add_option("--height", args->options.height, "Region height, px (default: camera's)");
  cmd->add_option("--exposure-us", args->options.exposure_us, "Exposure time, µs");
  cmd->add_option("--gain", args->options.gain, "Analog gain, camera units");
  cmd->add_option("--retries", args->options.retries,
                  "Re-triggers after an incomplete frame or a timeout")
      ->capture_default_str();
  cmd->footer(
      "Exit codes: 0 all frames saved, 1 a capture failure (message names the camera), 2 bad "
      "input.\n"
      "Example: rig capture --camera gige:127.0.0.1 --frames 10 --out /tmp/frames "
      "--trigger software");
  cmd->callback([&status, args] {
    status.code = run_command("capture", [&] { return run_capture(*args); });
  });
}

}  // namespace rig::cli
