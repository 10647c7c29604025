// rig::estimator::FrameFolder: where rig writes a frame for the external
// estimators when the sweep does not save its frames: a folder of the run's
// own, $TMPDIR/rig-frames-XXXXXX (mkdtemp: mode 0700, a name nobody else
// has), created at the first frame and removed with everything in it when
// the FrameFolder goes away.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

namespace rig::estimator {

class FrameFolder {
 public:
  FrameFolder() = default;
  ~FrameFolder();
  FrameFolder(const FrameFolder&) = delete;
  FrameFolder& operator=(const FrameFolder&) = delete;

  // Writes `image` (CV_8UC1 or CV_16UC1, as the camera delivered it) as a
  // lossless PNG (compression level 0, stored: every level is lossless and
  // level 0 takes half the CPU time of level 1 at 736x571,
  // tests/bench/bench_estimator.cpp) to FOLDER/frame.png, replacing the previous frame, and returns
  // its absolute path. The file is created new (O_EXCL, O_NOFOLLOW).
  // Throws std::runtime_error naming the folder or file when it cannot be
  // created, encoded or written.
  std::string write(const cv::Mat& image);

  // The folder, once created.
  const std::optional<std::filesystem::path>& folder() const { return folder_; }

 private:
  std::optional<std::filesystem::path> folder_;
};

}  // namespace rig::estimator
