// A serial line on one machine for Modbus RTU tests: two pseudo-terminals
// joined by socat. The drive's end is served by a simulated bench or drive
// emulator, the driver's end is opened through a bench URL. A pty carries
// bytes at any rate and whatever its serial settings, so what this tests is
// RTU framing, unit ids and the driver's silent intervals, not a line's timing.
#pragma once

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>

#include "child_process.hpp"

namespace rig_test {

class PtyPair {
 public:
  // Starts socat with the two ends as links in a new temporary folder.
  // Throws std::runtime_error when socat made no pair within 2 s (it takes
  // milliseconds).
  PtyPair() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "rig-pty-XXXXXX").string();
    if (mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
    dir_ = tmpl;
    drive_end_ = dir_ + "/drive";
    driver_end_ = dir_ + "/driver";
    socat_ = std::make_unique<ChildProcess>(std::vector<std::string>{
        "socat", "pty,raw,echo=0,link=" + drive_end_, "pty,raw,echo=0,link=" + driver_end_});
    struct stat st;
    for (int i = 0;
         i < 400 && (stat(drive_end_.c_str(), &st) != 0 || stat(driver_end_.c_str(), &st) != 0);
         ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (stat(driver_end_.c_str(), &st) != 0) {
      socat_.reset();
      std::filesystem::remove_all(dir_);
      throw std::runtime_error("socat made no pty pair in " + dir_);
    }
  }
  ~PtyPair() {
    socat_.reset();
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;

  const std::string& drive_end() const { return drive_end_; }
  const std::string& driver_end() const { return driver_end_; }

 private:
  std::string dir_, drive_end_, driver_end_;
  std::unique_ptr<ChildProcess> socat_;
};

}  // namespace rig_test
