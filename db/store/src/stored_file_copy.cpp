#include "db/store/stored_file_copy.hpp"

#include <stdlib.h>

#include <fstream>
#include <stdexcept>

namespace db::store {

StoredFileCopy::StoredFileCopy(const StoredFile& file, const std::string& fallback_name) {
  std::string pattern = (std::filesystem::temp_directory_path() / "rig-stored-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr)
    throw std::runtime_error("cannot create a temporary folder for the stored " + fallback_name);
  dir_ = pattern;
  const std::string name = std::filesystem::path(file.path).filename().string();
  path_ = (dir_ / (name.empty() ? fallback_name : name)).string();
  std::ofstream out(path_, std::ios::binary);
  out << file.content;
  if (!out) throw std::runtime_error("cannot write " + path_);
}

StoredFileCopy::~StoredFileCopy() {
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

}  // namespace db::store
