// OpenCV's image codecs (PNG, JPEG, TIFF, PNM, BMP: libopencv_imgcodecs),
// loaded the first time a program reads or writes an image.
//
// Why not linked: on Debian 12 that one library pulls about 140 others into
// a process (GDAL, GDCM, HDF5, Poppler, libheif and theirs), and resolving
// their symbols made every process that linked it take about 0.2 s to start
// (an empty program linked against rig's other libraries starts in 0.03 s).
// Most rig commands (`rig solve`, `rig bench`, `rig sweep` until it saves a
// frame) and most test processes never touch an image file; the ones that do
// pay for the load once, at their first image.
//
// Each function is OpenCV's function of the same name, with its arguments,
// results and exceptions (cv::Exception). Each throws ImageCodecsUnavailable
// when the library or one of its entry points cannot be loaded. Thread-safe:
// the library is loaded once per process. The cv::IMREAD_ and cv::IMWRITE_
// flags come from <opencv2/imgcodecs.hpp>, which this header includes; its
// functions must not be called directly (they are not linked, so a call to
// one fails to link).
#pragma once

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace vision {

// The image codec library (or one of its functions) could not be loaded; the
// message names the library and the loader's reason.
class ImageCodecsUnavailable : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// cv::imread: the image in the file at `path`, empty when it cannot be read.
cv::Mat imread(const std::string& path, int flags = cv::IMREAD_COLOR);

// cv::imwrite: writes `image` to `path` in the format its extension names;
// false when it cannot.
bool imwrite(const std::string& path, cv::InputArray image, const std::vector<int>& params = {});

// cv::imdecode: the image encoded in `bytes` (a vector or one row of CV_8U),
// empty when it does not decode.
cv::Mat imdecode(cv::InputArray bytes, int flags);

// cv::imencode: `image` encoded in the format `extension` names (".png"),
// into `encoded`; false when it cannot.
bool imencode(const std::string& extension, cv::InputArray image,
              std::vector<unsigned char>& encoded, const std::vector<int>& params = {});

}  // namespace vision
