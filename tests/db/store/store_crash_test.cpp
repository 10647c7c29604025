// Crash consistency: a child process appends positions in a loop
// and is killed with SIGKILL at random moments, several times. After every
// kill the file must pass PRAGMA integrity_check, every stored position must
// be complete and equal to what was written, the stored plan indices must be
// exactly 0 .. n-1 (no gap, no duplicate, nothing committed lost), and a new
// writer must continue from first_incomplete_position.
//
// The kill moments are drawn from a fixed seed, so every run asks for the
// same delays; where the kill actually lands still depends on the machine's
// speed, and the assertions are not timed: whatever instant it lands on
// (opening, WAL recovery, between positions, inside a transaction, during
// COMMIT), the same properties must hold.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <random>
#include <thread>

#include "db/store/store.hpp"
#include "store_fixture.hpp"

namespace {

// A position as large as a sweep's: 2 frames x 4 markers, 10 solvers x 2
// scopes, about a hundred rows, so that a kill often lands mid-transaction.
db::store::PositionRecord sweep_position(std::int64_t plan_index) {
  return db_test::make_position(plan_index, 2, 4, 10);
}

// The child: append from the resume point for ever, announcing each append
// with one byte on `announce` just before its transaction starts. Never
// returns; exits 3 if anything throws (a failure the parent reports).
[[noreturn]] void append_until_killed(const std::string& path, std::int64_t run, int announce) {
  try {
    db::store::Store store(path);
    for (;;) {
      const std::int64_t next = store.first_incomplete_position(run).value();
      const char byte = 1;
      if (write(announce, &byte, 1) != 1) _exit(4);
      store.append_position(run, sweep_position(next));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "child: %s\n", e.what());
  }
  _exit(3);
}

std::string integrity_check(const std::string& path) {
  sqlite3* raw = nullptr;
  sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* statement = nullptr;
  sqlite3_prepare_v2(raw, "PRAGMA integrity_check", -1, &statement, nullptr);
  std::string result;
  while (sqlite3_step(statement) == SQLITE_ROW) {
    result += reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
  }
  sqlite3_finalize(statement);
  sqlite3_close(raw);
  return result;
}

// Forks a writer that appends from the resume point, kills it with SIGKILL
// at a random moment and sets `announced` to the appends it had started.
// Every fourth kill is early: while the child opens the file (and recovers
// the WAL the previous kill left) or runs its first query. The others let
// 1-20 appends start, then kill somewhere inside or after the next one (a
// sweep position takes of the order of a millisecond).
void kill_a_writer(const std::string& path, std::int64_t run, int kill_number, std::mt19937& random,
                   std::int64_t& announced) {
  int pipe_fds[2];
  ASSERT_EQ(pipe(pipe_fds), 0);
  // No Store is open in the parent here: an SQLite connection must not
  // cross a fork.
  const pid_t child = fork();
  ASSERT_NE(child, -1);
  if (child == 0) {
    close(pipe_fds[0]);
    append_until_killed(path, run, pipe_fds[1]);
  }
  close(pipe_fds[1]);
  announced = 0;
  if (kill_number % 4 == 3) {
    std::this_thread::sleep_for(
        std::chrono::microseconds(std::uniform_int_distribution<int>(0, 3000)(random)));
  } else {
    const int appends = std::uniform_int_distribution<int>(1, 20)(random);
    char byte = 0;
    while (announced < appends && read(pipe_fds[0], &byte, 1) == 1) {
      ++announced;
    }
    std::this_thread::sleep_for(
        std::chrono::microseconds(std::uniform_int_distribution<int>(0, 2000)(random)));
  }
  kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  // Every append the child started was announced; the unread announcements
  // are still in the pipe.
  char drained[256];
  for (ssize_t n; (n = read(pipe_fds[0], drained, sizeof drained)) > 0;)
    announced += n;
  close(pipe_fds[0]);
  // Killed by us, not exited on an error of its own.
  ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
      << "child exited with status " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

// What the kills have left so far.
struct CrashTally {
  std::int64_t stored = 0;  // positions verified so far: 0 .. stored-1
  int rounds_that_added = 0;
  int kills_inside_an_append = 0;  // for information: depends on timing
};

// The file after a kill of a writer that had started `announced` appends:
// intact, its plan indices exactly 0 .. n-1 with nothing committed lost,
// every new position whole, and only the last append possibly missing.
void check_after_kill(const std::string& path, std::int64_t run, std::int64_t announced,
                      CrashTally& tally) {
  ASSERT_EQ(integrity_check(path), "ok");
  db::store::Store store(path);
  const std::vector<std::int64_t> indices = store.completed_position_indices(run);
  ASSERT_GE(static_cast<std::int64_t>(indices.size()), tally.stored);
  for (std::size_t i = 0; i < indices.size(); ++i)
    ASSERT_EQ(indices[i], std::int64_t(i));
  EXPECT_EQ(store.first_incomplete_position(run), std::int64_t(indices.size()));
  // The new positions field by field; the earlier ones were compared in
  // earlier rounds and are re-counted below.
  for (std::int64_t i = tally.stored; i < std::int64_t(indices.size()); ++i) {
    ASSERT_EQ(store.position(run, i), sweep_position(i)) << "plan index " << i;
  }
  // Each append the child started is either all in the file or not at
  // all: only the last one can be missing (the kill landed inside it).
  const std::int64_t added = std::int64_t(indices.size()) - tally.stored;
  ASSERT_TRUE(added == announced || added == announced - 1)
      << added << " positions added, " << announced << " appends started";
  if (added == announced - 1) ++tally.kills_inside_an_append;
  if (added > 0) ++tally.rounds_that_added;
  tally.stored = std::int64_t(indices.size());
  // 2 frames x 10 solvers x 2 scopes estimates per position, none partial.
  EXPECT_EQ(store.estimates(run, "solver_9").size(), std::size_t(tally.stored) * 4);
}

TEST(StoreCrash, KeepsEveryCommittedPositionWholeAcrossRepeatedSigkill) {
  db_test::ScratchDir dir;
  const std::string path = dir.file("crash.db");
  std::int64_t run = 0;
  {
    db::store::Store store(path);
    run = store.start_run(db_test::make_run_description(1'000'000));
  }
  std::mt19937 random(20260611);

  constexpr int kKills = 12;
  CrashTally tally;
  for (int kill_number = 0; kill_number < kKills; ++kill_number) {
    SCOPED_TRACE("kill " + std::to_string(kill_number));
    std::int64_t announced = 0;
    ASSERT_NO_FATAL_FAILURE(kill_a_writer(path, run, kill_number, random, announced));
    ASSERT_NO_FATAL_FAILURE(check_after_kill(path, run, announced, tally));
  }
  // The kills did interrupt a writer that was making progress: not timed,
  // since a round that read a second announcement killed after a commit.
  EXPECT_GE(tally.rounds_that_added, 1);
  RecordProperty("kills_inside_an_append", tally.kills_inside_an_append);
  RecordProperty("positions_before_resume", static_cast<int>(tally.stored));

  // A resumed sweep continues from the first missing index: nothing skipped,
  // nothing written twice.
  db::store::Store store(path);
  for (int i = 0; i < 3; ++i) {
    store.append_position(run, sweep_position(store.first_incomplete_position(run).value()));
  }
  const std::vector<std::int64_t> indices = store.completed_position_indices(run);
  ASSERT_EQ(std::int64_t(indices.size()), tally.stored + 3);
  for (std::size_t i = 0; i < indices.size(); ++i)
    EXPECT_EQ(indices[i], std::int64_t(i));
  EXPECT_THROW(store.append_position(run, sweep_position(0)), db::store::DuplicatePosition);
}

}  // namespace
