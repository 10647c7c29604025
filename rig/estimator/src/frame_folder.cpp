#include "rig/estimator/frame_folder.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "vision/image_codecs.hpp"

namespace rig::estimator {

FrameFolder::~FrameFolder() {
  if (!folder_) return;
  std::error_code ec;
  std::filesystem::remove_all(*folder_, ec);
}

std::string FrameFolder::write(const cv::Mat& image) {
  if (!folder_) {
    std::string pattern = (std::filesystem::temp_directory_path() / "rig-frames-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr)
      throw std::runtime_error(pattern +
                               ": cannot create a folder for the external estimators' "
                               "frames: " +
                               std::strerror(errno) + "; expected a writable TMPDIR");
    folder_ = pattern;
  }
  std::vector<unsigned char> png;
  if (!vision::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, 0}))
    throw std::runtime_error("cannot encode the frame as PNG for the external estimators");
  const std::filesystem::path file = *folder_ / "frame.png";
  if (::unlink(file.c_str()) == -1 && errno != ENOENT)
    throw std::runtime_error(file.string() +
                             ": cannot remove the previous frame: " + std::strerror(errno));
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0600);
  if (fd == -1)
    throw std::runtime_error(file.string() + ": cannot create: " + std::strerror(errno));
  std::size_t done = 0;
  while (done < png.size()) {
    const ssize_t n = ::write(fd, png.data() + done, png.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      throw std::runtime_error(file.string() + ": cannot write: " + why);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) == -1)
    throw std::runtime_error(file.string() + ": cannot write: " + std::strerror(errno));
  return file.string();
}

}  // namespace rig::estimator
