// vision::ReplaySource: recorded frames, in order, for re-processing a sweep.
//
// A folder is read in file-name order (only image files: png, jpg, jpeg, bmp,
// tif, tiff, pgm, ppm, pnm); a list of paths is read in the given order.
// Images are delivered as 8-bit grey (CV_8UC1), what the detector reads.
// trigger() does nothing: every grab() takes the next image.
//
// A file that does not decode throws CaptureError naming that file, and the
// replay moves past it, so the next grab() delivers the next image. After the
// last image grab() throws EndOfFrames.
#pragma once

#include <string>
#include <vector>

#include "vision/frame_source.hpp"

namespace vision {

class ReplaySource final : public FrameSource {
 public:
  // Every image file of `folder`, sorted by name. The folder is listed by open().
  explicit ReplaySource(std::string folder);
  // Exactly these files, in this order.
  explicit ReplaySource(std::vector<std::string> paths);

  // Lists the folder. Throws CaptureError when it is missing, not a folder, or
  // holds no image file.
  void open() override;
  void trigger() override {}
  Frame grab(std::chrono::milliseconds timeout) override;
  void close() override { opened_ = false; }

  std::string name() const override { return "replay:" + folder_; }
  CaptureCounters counters() const override { return counters_; }
  // The files to replay, in order (after open() for a folder).
  const std::vector<std::string>& paths() const { return paths_; }

 private:
  std::string folder_;
  std::vector<std::string> paths_;
  size_t next_ = 0;
  bool opened_ = false;
  CaptureCounters counters_;
};

}  // namespace vision
