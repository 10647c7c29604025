#include "vision/replay_source.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <system_error>
#include <utility>

#include "vision/detector_image.hpp"

namespace vision {
namespace {

bool is_image_file(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const char* const kExtensions[] = {".png",  ".jpg", ".jpeg", ".bmp", ".tif",
                                            ".tiff", ".pgm", ".ppm",  ".pnm"};
  return std::find(std::begin(kExtensions), std::end(kExtensions), ext) != std::end(kExtensions);
}

}  // namespace

ReplaySource::ReplaySource(std::string folder) : folder_(std::move(folder)) {}

ReplaySource::ReplaySource(std::vector<std::string> paths)
    : folder_("(list)"), paths_(std::move(paths)) {}

void ReplaySource::open() {
  if (opened_) return;
  if (folder_ != "(list)") {
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_directory(folder_, ec))
      throw CaptureError(name(), "not a folder of images (missing or not a directory)");
    paths_.clear();
    for (const auto& entry : fs::directory_iterator(folder_, ec))
      if (entry.is_regular_file() && is_image_file(entry.path()))
        paths_.push_back(entry.path().string());
    if (ec) throw CaptureError(name(), "cannot list the folder: " + ec.message());
    std::sort(paths_.begin(), paths_.end());
  }
  if (paths_.empty()) throw CaptureError(name(), "holds no image file (png, jpg, bmp, tif, pgm)");
  next_ = 0;
  counters_ = {};
  opened_ = true;
}

Frame ReplaySource::grab(std::chrono::milliseconds /*timeout*/) {
  if (!opened_) throw CaptureError(name(), "grab() before open()");
  if (next_ >= paths_.size())
    throw EndOfFrames(name(), "all " + std::to_string(paths_.size()) + " images delivered");
  const size_t index = next_++;
  const std::string& path = paths_[index];
  cv::Mat image;
  try {
    image = read_image(path, cv::IMREAD_GRAYSCALE);
  } catch (const ImageError& e) {
    ++counters_.incomplete;
    throw CaptureError(name(), "frame " + std::to_string(index) + ": " + e.what());
  }
  Frame frame;
  frame.image = std::move(image);
  frame.frame_id = index;
  frame.host_time = std::chrono::system_clock::now();
  frame.origin = path;
  ++counters_.delivered;
  return frame;
}

}  // namespace vision
