// A file stored in a run (RunDescription: calibration, target layout, ...)
// written back to disk for the loaders that take a path.
#pragma once

#include <filesystem>
#include <string>

#include "db/store/records.hpp"

namespace db::store {

// Writes `file.content` to a private temporary folder (mkdtemp under the
// system's temporary directory), under the stored file's own name, or under
// `fallback_name` when the stored path has none. The folder and the file are
// removed when the copy goes out of scope.
// Errors: std::runtime_error naming `fallback_name` or the path when the
// folder cannot be created or the file cannot be written.
class StoredFileCopy {
 public:
  StoredFileCopy(const StoredFile& file, const std::string& fallback_name);
  ~StoredFileCopy();
  StoredFileCopy(const StoredFileCopy&) = delete;
  StoredFileCopy& operator=(const StoredFileCopy&) = delete;

  // The copy's path, valid while the copy lives.
  const std::string& path() const { return path_; }

 private:
  std::filesystem::path dir_;
  std::string path_;
};

}  // namespace db::store
