#pragma once
// The raw frames a sweep saved ([capture] save_frames): each frame record
// holds the file's path and the SHA-256 of its bytes (records.hpp,
// FrameRecord::image_path, image_sha256), so that a reader can tell a file
// that changed since the run from the frame it measured.

#include <stdexcept>
#include <string>

namespace db::store {

class SavedFrameError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The bytes of the saved frame at `path`, checked against `sha256` (64
// lowercase hex characters, as the run stored it). Throws SavedFrameError
// naming the file: "cannot read recorded frame PATH: REASON" when it cannot
// be opened or read, "recorded frame PATH has SHA-256 ABC... but the run
// stored DEF...; the file changed since it was recorded" when the bytes
// differ.
std::string read_saved_frame(const std::string& path, const std::string& sha256);

}  // namespace db::store
