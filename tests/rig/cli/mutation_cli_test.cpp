// The exit-code and message contract as a class: the repository's own valid
// inputs (a sweep file, the drive profile and plan CSV it names, the paper
// camera's calibration, the sample problem, a rendered frame as PNG and PGM,
// a small run database) are mutated a few hundred times (bytes flipped, the
// file cut short, a number replaced by 1e999999, -0, nan or the like, a key
// removed, a value nested deep), and the real rig subcommand that reads each
// is run on it. Every run must exit by itself (no signal, no hang) with a
// documented code (0 ok, 1 runtime fault, 2 bad input), and a non-zero exit
// must name the mutated file on stderr, or the next step's own refusal that
// shows the mutated file was accepted whole. The mutations come from one
// seeded generator: the same cases on every run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "file_bytes.hpp"
#include "sim/scene/renderer.hpp"
#include "synthetic_run.hpp"
#include "vision/image_codecs.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

const std::string kConfig = std::string(RIG_SOURCE_DIR) + "/config";

void spill(const fs::path& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes;
}

struct Outcome {
  bool signalled = false, hung = false;
  int exit_code = -1;
  std::string err;
};

// Runs bin/rig with `args` (no shell), stdin and stdout /dev/null, stderr
// captured; killed after 30 s (a hang is a finding: the slowest run here
// takes well under a second).
Outcome run_rig(const std::vector<std::string>& args, const fs::path& err_file) {
  std::vector<std::string> argv_text = {std::string(RIG_BINARY_DIR) + "/bin/rig"};
  argv_text.insert(argv_text.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : argv_text)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  pid_t pid = -1;
  Outcome o;
  const int spawned = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    o.err = "posix_spawn failed";
    return o;
  }
  int status = 0;
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      o.hung = true;
      break;
    }
    std::this_thread::sleep_for(2ms);
  }
  o.signalled = !o.hung && WIFSIGNALED(status);
  if (WIFEXITED(status)) o.exit_code = WEXITSTATUS(status);
  o.err = rig_test::file_bytes(err_file);
  return o;
}

// One generator for every choice, so that a case is its seed and index.
class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : random_(seed) {}
  // A number in [0, n): the engine's raw output, the same on every library.
  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(random_() % n); }

  std::string flip_bytes(std::string s, std::string& what) {
    if (s.empty()) return s;
    const std::size_t flips = 1 + below(3);
    for (std::size_t i = 0; i < flips; ++i) {
      const std::size_t at = below(s.size());
      s[at] = static_cast<char>(s[at] ^ static_cast<char>(1 + below(255)));
      what += " flip@" + std::to_string(at);
    }
    return s;
  }
  std::string truncate(const std::string& s, std::string& what) {
    const std::size_t at = below(s.size());
    what += " cut@" + std::to_string(at);
    return s.substr(0, at);
  }
  // A number token of the text replaced by one no reader should take whole.
  std::string replace_number(const std::string& s, std::string& what) {
    static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]*)?([eE][-+]?[0-9]+)?)");
    static const std::vector<std::string> kHostile = {
        "1e999999", "-1e999999", "-0", "nan", "inf", "1e-999999", "99999999999999999999",
        "0",        "-1"};
    std::vector<std::pair<std::size_t, std::size_t>> spans;
    for (auto it = std::sregex_iterator(s.begin(), s.end(), kNumber); it != std::sregex_iterator();
         ++it)
      spans.emplace_back(static_cast<std::size_t>(it->position()),
                         static_cast<std::size_t>(it->length()));
    if (spans.empty()) return flip_bytes(s, what);
    const auto [at, length] = spans[below(spans.size())];
    const std::string& by = kHostile[below(kHostile.size())];
    what += " number@" + std::to_string(at) + "=" + by;
    return s.substr(0, at) + by + s.substr(at + length);
  }
  // A line holding `marker` (a key's "=" or ":", a CSV row) left out.
  std::string remove_line(const std::string& s, const std::string& marker, std::string& what) {
    std::vector<std::string> lines;
    std::istringstream in(s);
    for (std::string line; std::getline(in, line);)
      lines.push_back(line);
    std::vector<std::size_t> keyed;
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (lines[i].find(marker) != std::string::npos && lines[i].rfind('#', 0) != 0)
        keyed.push_back(i);
    if (keyed.empty()) return truncate(s, what);
    const std::size_t drop = keyed[below(keyed.size())];
    what += " drop line " + std::to_string(drop + 1);
    std::string out;
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (i != drop) out += lines[i] + "\n";
    return out;
  }
  // A number token replaced by itself nested 10 to 100,000 levels deep in
  // the format's brackets.
  std::string nest(const std::string& s, std::string& what) {
    static const std::size_t kDepths[] = {10, 65, 1000, 100000};
    const std::size_t depth = kDepths[below(4)];
    std::string inner_what;
    const std::string marked = replace_number_with(s, "@NEST@", inner_what);
    const std::size_t at = marked.find("@NEST@");
    if (at == std::string::npos) return flip_bytes(s, what);
    what += " nest" + std::to_string(depth) + inner_what;
    return marked.substr(0, at) + std::string(depth, '[') + "1" + std::string(depth, ']') +
           marked.substr(at + 6);
  }

 private:
  std::string replace_number_with(const std::string& s, const std::string& by, std::string& what) {
    static const std::regex kNumber(R"(-?[0-9]+(\.[0-9]*)?)");
    std::vector<std::size_t> starts, lengths;
    for (auto it = std::sregex_iterator(s.begin(), s.end(), kNumber); it != std::sregex_iterator();
         ++it) {
      starts.push_back(static_cast<std::size_t>(it->position()));
      lengths.push_back(static_cast<std::size_t>(it->length()));
    }
    if (starts.empty()) return s;
    const std::size_t k = below(starts.size());
    what += "@" + std::to_string(starts[k]);
    return s.substr(0, starts[k]) + by + s.substr(starts[k] + lengths[k]);
  }
  std::mt19937_64 random_;
};

// A text input's mutation: one of the five kinds, in turn with the case
// index so that every kind is exercised on every input.
std::string mutate_text(Mutator& m, const std::string& text, const std::string& key_marker,
                        int index, std::string& what) {
  switch (index % 5) {
    case 0:
      return m.flip_bytes(text, what);
    case 1:
      return m.truncate(text, what);
    case 2:
      return m.replace_number(text, what);
    case 3:
      return m.remove_line(text, key_marker, what);
    default:
      return m.nest(text, what);
  }
}

// A binary input's mutation: bytes flipped or the file cut short.
std::string mutate_bytes(Mutator& m, const std::string& bytes, int index, std::string& what) {
  return index % 2 == 0 ? m.flip_bytes(bytes, what) : m.truncate(bytes, what);
}

class MutatedInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "rig-mutation-XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Runs one case and records a breach of the contract. `accepted` is the
  // next step's refusal that shows the mutated input was taken whole.
  void check(const std::string& input, const std::string& what, const fs::path& file,
             const std::vector<std::string>& args, const std::string& accepted = "") {
    const Outcome o = run_rig(args, dir_ / "stderr.txt");
    Counts& c = counts_[input];
    ++c.runs;
    if (o.exit_code >= 0 && o.exit_code <= 2) ++c.by_exit[o.exit_code];
    if (o.exit_code == 0 || (!accepted.empty() && o.err.find(accepted) != std::string::npos))
      ++c.accepted;
    std::string breach;
    if (o.hung)
      breach = "hung (killed after 30 s)";
    else if (o.signalled)
      breach = "ended by a signal";
    else if (o.exit_code < 0 || o.exit_code > 2)
      breach = "exit " + std::to_string(o.exit_code) + ", expected 0, 1 or 2";
    else if (o.exit_code != 0 && o.err.find(file.string()) == std::string::npos &&
             (accepted.empty() || o.err.find(accepted) == std::string::npos))
      breach = "exit " + std::to_string(o.exit_code) + " without naming " + file.string();
    if (!breach.empty()) {
      ++c.breaches;
      ADD_FAILURE() << input << " [" << what << " ]: " << breach
                    << "; stderr: " << o.err.substr(0, 600);
    }
  }

  void report_counts() const {
    int total = 0;
    for (const auto& [input, c] : counts_) {
      std::cout << "mutated " << input << ": " << c.runs << " runs, exit 0/1/2 = " << c.by_exit[0]
                << "/" << c.by_exit[1] << "/" << c.by_exit[2] << ", taken whole " << c.accepted
                << ", breaches " << c.breaches << "\n";
      total += c.runs;
    }
    std::cout << "mutated inputs: " << total << " runs\n";
  }

  struct Counts {
    int runs = 0, breaches = 0, accepted = 0;
    int by_exit[3] = {0, 0, 0};
  };
  fs::path dir_;
  std::map<std::string, Counts> counts_;
};

// The sweep file, its drive profile and its plan CSV, read by `rig sweep
// --replay 1` into a database that does not exist: every file the sweep file
// names is read and checked first, and a sweep whose files were all taken
// stops at the missing database (exit 2), before any bench, camera or
// network is used; telemetry is on ipc:// paths in the scratch folder.
TEST_F(MutatedInputs, SweepFileDriveProfileAndPlanCsvEndInADocumentedExitNamingTheFile) {
  const fs::path profile = dir_ / "profile.toml", plan = dir_ / "plan.csv",
                 camera = dir_ / "camera.yaml", sweep = dir_ / "sweep.toml";
  const std::string profile_text = rig_test::file_bytes(kConfig + "/benches/sim.toml");
  const std::string plan_text = rig_test::file_bytes(kConfig + "/plans/example.csv");
  spill(profile, profile_text);
  spill(plan, plan_text);
  spill(camera, rig_test::file_bytes(kConfig + "/cameras/sony_xc555.yaml"));
  const std::string sweep_text =
      "[plan]\nkind = \"csv\"\nfile = \"" + plan.string() +
      "\"\n\n[capture]\ncamera = \"gige:127.0.0.1\"\ncalibration = \"" + camera.string() +
      "\"\nframes_per_position = 2\ngrab_timeout_ms = 500\n\n[bench]\nurl = "
      "\"modbus-tcp://127.0.0.1:1502\"\nprofile = \"" +
      profile.string() + "\"\nspeed_mm_s = 100\n\n[faults]\non_alarm = \"abort\"\n\n[target]\n" +
      "layout = \"" + kConfig + "/targets/paper.toml\"\n\n[rig]\nfile = \"" + kConfig +
      "/rigs/sim.toml\"\n\n[telemetry]\npublish = \"ipc://" + (dir_ / "publish").string() +
      "\"\ncontrol = \"ipc://" + (dir_ / "control").string() + "\"\n\n[database]\npath = \"" +
      (dir_ / "unused.db").string() + "\"\n";
  spill(sweep, sweep_text);
  const std::string missing_db = (dir_ / "missing.db").string();
  const std::vector<std::string> args = {"sweep", sweep.string(), "--db", missing_db, "--replay",
                                         "1",     "--no-progress"};
  const std::string accepted = "database " + missing_db + " does not exist";
  // The unmutated files are taken whole.
  const Outcome valid = run_rig(args, dir_ / "stderr.txt");
  ASSERT_EQ(valid.exit_code, 2) << valid.err;
  ASSERT_NE(valid.err.find(accepted), std::string::npos) << valid.err;

  Mutator m(20261202);
  struct Input {
    std::string name;
    fs::path file;
    std::string text, key_marker;
    int cases;
  };
  const std::vector<Input> inputs = {{"sweep file", sweep, sweep_text, "=", 60},
                                     {"drive profile", profile, profile_text, "=", 50},
                                     {"plan CSV", plan, plan_text, ",", 40}};
  for (const Input& in : inputs) {
    for (int i = 0; i < in.cases; ++i) {
      std::string what;
      spill(in.file, mutate_text(m, in.text, in.key_marker, i, what));
      check(in.name, what, in.file, args, accepted);
    }
    spill(in.file, in.text);
  }
  report_counts();
}

// The calibration, the problem, a frame: `rig detect` and `rig solve`.
TEST_F(MutatedInputs, CalibrationProblemAndImagesEndInADocumentedExitNamingTheFile) {
  const sim::scene::SceneRenderer renderer(vision::Camera::paper_default(),
                                           vision::Target::paper_default(), vision::Codebook());
  vision::Pose pose;
  pose.R = Eigen::Matrix3d(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 0.5, 0).normalized()));
  pose.t = Eigen::Vector3d(0.01, 0.0, 0.5);
  const cv::Mat frame = renderer.render(pose, 3).image;
  const fs::path png = dir_ / "frame.png", pgm = dir_ / "frame.pgm", good = dir_ / "good.png";
  ASSERT_TRUE(vision::imwrite(png.string(), frame));
  ASSERT_TRUE(vision::imwrite(pgm.string(), frame));
  ASSERT_TRUE(vision::imwrite(good.string(), frame));
  const std::string png_bytes = rig_test::file_bytes(png), pgm_bytes = rig_test::file_bytes(pgm);
  const fs::path camera = dir_ / "camera.yaml", problem = dir_ / "problem.json";
  const std::string camera_text = rig_test::file_bytes(kConfig + "/cameras/sony_xc555.yaml");
  const std::string problem_text = rig_test::file_bytes(kConfig + "/problems/paper_marker.json");

  Mutator m(20101117);
  for (int i = 0; i < 50; ++i) {
    std::string what;
    spill(camera, mutate_text(m, camera_text, ":", i, what));
    check("calibration", what, camera, {"detect", good.string(), "--camera", camera.string()});
  }
  for (int i = 0; i < 50; ++i) {
    std::string what;
    spill(problem, mutate_text(m, problem_text, "\":", i, what));
    check("problem JSON", what, problem, {"solve", problem.string()});
  }
  for (int i = 0; i < 20; ++i) {
    std::string what;
    spill(png, mutate_bytes(m, png_bytes, i, what));
    check("PNG image", what, png, {"detect", png.string()});
  }
  // A PGM's header is text: its width, height and maximum are numbers.
  for (int i = 0; i < 20; ++i) {
    std::string what;
    const std::string header = pgm_bytes.substr(0, 20);
    const std::string mutated = i % 2 == 0 ? m.replace_number(header, what) + pgm_bytes.substr(20)
                                           : mutate_bytes(m, pgm_bytes, i / 2, what);
    spill(pgm, mutated);
    check("PGM image", what, pgm, {"detect", pgm.string()});
  }
  report_counts();
}

// A small run database, read by `rig report`: its bytes, and its values
// through SQL (a cell set to NULL, text, an infinite or deeply nested value,
// a row removed), as a damaged or foreign file could hold them.
TEST_F(MutatedInputs, ARunDatabaseEndsInADocumentedExitNamingTheFile) {
  const fs::path original = dir_ / "original.db", db = dir_ / "run.db";
  rig_test::SyntheticRunSpec spec;
  spec.seed = 7;
  spec.positions = 8;
  spec.frames_per_position = 2;
  spec.solvers = rig_test::paper_like_solvers();
  rig_test::write_synthetic_run(original.string(), spec);
  const std::string bytes = rig_test::file_bytes(original);
  const std::vector<std::string> args = {"report", db.string(), "--out", (dir_ / "out").string()};
  spill(db, bytes);
  const Outcome valid = run_rig(args, dir_ / "stderr.txt");
  ASSERT_EQ(valid.exit_code, 0) << valid.err;

  std::vector<std::pair<std::string, std::string>> columns;  // table, column
  {
    sqlite3* connection = nullptr;
    ASSERT_EQ(sqlite3_open_v2(original.c_str(), &connection, SQLITE_OPEN_READONLY, nullptr),
              SQLITE_OK);
    sqlite3_stmt* statement = nullptr;
    sqlite3_prepare_v2(connection,
                       "SELECT m.name, p.name FROM sqlite_master m, pragma_table_info(m.name) p "
                       "WHERE m.type = 'table' AND m.name NOT LIKE 'sqlite_%' ORDER BY 1, 2",
                       -1, &statement, nullptr);
    while (sqlite3_step(statement) == SQLITE_ROW)
      columns.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(statement, 0)),
                           reinterpret_cast<const char*>(sqlite3_column_text(statement, 1)));
    sqlite3_finalize(statement);
    sqlite3_close(connection);
  }
  ASSERT_FALSE(columns.empty());
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  const std::vector<std::string> values = {
      "NULL", "'x'", "9e999", "-9e999", "-0.0", "''", "'" + deep + "'", "-1", "99999999999"};
  Mutator m(19700101);
  for (int i = 0; i < 40; ++i) {
    std::string what;
    if (i % 2 == 0) {
      spill(db, mutate_bytes(m, bytes, i / 2, what));
    } else {
      spill(db, bytes);
      const auto& [table, column] = columns[m.below(columns.size())];
      const std::string sql =
          m.below(4) == 0
              ? "DELETE FROM " + table + " WHERE rowid IN (SELECT rowid FROM " + table +
                    " ORDER BY rowid LIMIT 1 OFFSET " + std::to_string(m.below(3)) + ")"
              : "UPDATE " + table + " SET " + column + " = " + values[m.below(values.size())] +
                    " WHERE rowid = (SELECT min(rowid) FROM " + table + ")";
      what += " " + sql.substr(0, 120);
      sqlite3* connection = nullptr;
      ASSERT_EQ(sqlite3_open(db.c_str(), &connection), SQLITE_OK);
      sqlite3_exec(connection, sql.c_str(), nullptr, nullptr, nullptr);
      sqlite3_close(connection);
    }
    check("run database", what, db, args);
  }
  report_counts();
}

}  // namespace
