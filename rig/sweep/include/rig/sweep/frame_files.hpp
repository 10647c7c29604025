// Where a sweep writes the frames it saves (sweep file `[capture]
// save_frames = "DIR"`), and how: only new files, in a folder no other
// database or run shares (docs/sweep-file.md, docs/data-flow.md).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace rig::sweep {

// The folder of the database's frames under `frames_dir`:
// DIR/<database stem>-<first 12 hex digits of the SHA-256 of the database's
// absolute path>, so that two databases never share a folder.
std::filesystem::path database_frames_folder(const std::string& frames_dir,
                                             const std::string& database);

// The folder of run `run_id`'s frames: database_frames_folder/run<N>. Frame
// k of position i is p<i>_f<k>.png in it; the database stores each path.
std::filesystem::path run_frames_folder(const std::string& frames_dir, const std::string& database,
                                        std::int64_t run_id);

// Creates `folder` (and its parents) and checks that it is a real folder
// (not a symbolic link) in which a new file can be created. Throws
// std::runtime_error "FOLDER: PROBLEM; expected a folder rig can create
// files in" otherwise. Called before the bench moves.
void prepare_frames_folder(const std::filesystem::path& folder);

// Writes `bytes` to `file`, which must not exist: opened O_CREAT | O_EXCL |
// O_NOFOLLOW, so that nothing planted at the path (a symbolic link, another
// run's file) is followed or overwritten. The one exception is a regular
// file left by this run's own interrupted position (a crash between writing
// the frame and storing the position); `replace_leftover` true removes such a
// file (never what a link points to) and writes anew. Throws
// std::runtime_error naming the file and the reason otherwise.
void write_new_file(const std::filesystem::path& file, std::string_view bytes,
                    bool replace_leftover);

}  // namespace rig::sweep
