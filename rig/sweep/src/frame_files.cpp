#include "rig/sweep/frame_files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "db/store/sha256.hpp"

namespace rig::sweep {
namespace {

namespace fs = std::filesystem;

std::runtime_error file_error(const fs::path& file, const std::string& what) {
  return std::runtime_error("frame file " + file.string() + ": " + what);
}

// Opens `file` for writing only if it does not exist and is not a link.
int open_new(const fs::path& file) {
  return ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
}

}  // namespace

fs::path database_frames_folder(const std::string& frames_dir, const std::string& database) {
  std::error_code ec;
  fs::path absolute = fs::weakly_canonical(fs::absolute(database), ec);
  if (ec) absolute = fs::absolute(database);
  const std::string hash = db::store::sha256_hex(absolute.string()).substr(0, 12);
  return fs::path(frames_dir) / (fs::path(database).stem().string() + "-" + hash);
}

fs::path run_frames_folder(const std::string& frames_dir, const std::string& database,
                           std::int64_t run_id) {
  return database_frames_folder(frames_dir, database) / ("run" + std::to_string(run_id));
}

void prepare_frames_folder(const fs::path& folder) {
  const auto fail = [&](const std::string& what) {
    return std::runtime_error(folder.string() + ": " + what +
                              "; expected a folder rig can create files in");
  };
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw fail("cannot be created (" + ec.message() + ")");
  struct stat st {};
  if (::lstat(folder.c_str(), &st) != 0) throw fail(std::strerror(errno));
  if (S_ISLNK(st.st_mode)) throw fail("is a symbolic link");
  if (!S_ISDIR(st.st_mode)) throw fail("is not a folder");
  // The one test that answers for every cause (permissions, read-only file
  // system, ACLs): create a file exclusively, then remove it.
  const fs::path probe = folder / (".rig-write-check-" + std::to_string(::getpid()));
  const int fd = open_new(probe);
  if (fd < 0)
    throw fail(std::string("a file cannot be created in it (") + std::strerror(errno) + ")");
  ::close(fd);
  ::unlink(probe.c_str());
}

void write_new_file(const fs::path& file, std::string_view bytes, bool replace_leftover) {
  int fd = open_new(file);
  if (fd < 0 && errno == EEXIST && replace_leftover) {
    struct stat st {};
    if (::lstat(file.c_str(), &st) == 0 && S_ISREG(st.st_mode) && ::unlink(file.c_str()) == 0)
      fd = open_new(file);
    else
      errno = EEXIST;
  }
  if (fd < 0) {
    const int error = errno;
    throw file_error(file, error == EEXIST || error == ELOOP
                               ? "exists already (a file or link no run of this database wrote); "
                                 "expected a new file"
                               : std::string("cannot be created (") + std::strerror(error) + ")");
  }
  std::size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      throw file_error(file, std::string("cannot be written (") + std::strerror(error) + ")");
    }
    written += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0)
    throw file_error(file, std::string("cannot be written (") + std::strerror(errno) + ")");
}

}  // namespace rig::sweep
