// rig report over a database of 1,000,000 estimates (target: at most 10 s
// on a 2-core machine like CI's). The database is written once by the
// synthetic-run fixture (10,000 positions x 5 frames x 10 solvers x 2 scopes,
// 4 detections per frame, non-durable commits) and reused: set
// RIG_BENCH_REPORT_DB to keep it between runs (default: a file in /tmp that is
// removed at exit).
//  - BM_StudyRun: loading the run (the three indexed passes) and every statistic.
//  - BM_ReportWrite: the whole `rig report`: study, HTML, JSON and CSV.
//  - BM_SqliteEstimateScan: the peer, SQLite alone: every estimate row read
//    in row order with the columns the report reads (22 per row, each
//    fetched), nothing done with them. BM_StudyRun over it is the report's
//    time in units of SQLite's own floor; the rest is ours.
// Run: scripts/bench bench_report   (or build-*/tests/bench/bench_report)
#include <benchmark/benchmark.h>
#include <sqlite3.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "db/report/report.hpp"
#include "synthetic_run.hpp"

namespace {

rig_test::SyntheticRunSpec million_estimates() {
  rig_test::SyntheticRunSpec spec;
  spec.positions = 10000;
  spec.frames_per_position = 5;
  const auto paper = rig_test::paper_like_solvers();
  for (const char* name : {"analytic", "oi", "hybrid_oi", "ekf", "hybrid_ekf", "ippe", "lm",
                           "opencv_ippe_square", "opencv_iterative", "opencv_sqpnp"}) {
    rig_test::SyntheticSolver s = paper[1];
    s.name = name;
    if (std::string(name) == "analytic" || std::string(name) == "opencv_ippe_square")
      s.single_square_only = true;
    if (std::string(name).find("ippe") != std::string::npos) s.ambiguity_ratio = 0.5;
    spec.solvers.push_back(s);
  }
  return spec;
}

// The database, written on first use.
const std::string& database() {
  static const std::string path = [] {
    const char* env = std::getenv("RIG_BENCH_REPORT_DB");
    std::string p =
        env != nullptr ? env : "/tmp/rig-bench-report-" + std::to_string(getpid()) + ".db";
    if (!std::filesystem::exists(p)) rig_test::write_synthetic_run(p, million_estimates());
    if (env == nullptr) {
      std::atexit([] {
        const std::string base = "/tmp/rig-bench-report-" + std::to_string(getpid()) + ".db";
        for (const char* suffix : {"", "-wal", "-shm"})
          std::filesystem::remove(base + suffix);
      });
    }
    return p;
  }();
  return path;
}

void BM_StudyRun(benchmark::State& state) {
  const std::string& db = database();
  std::size_t estimates = 0;
  for (auto _ : state) {
    const db::report::RunStudy study = db::report::study_run(db, db::report::ReportOptions{});
    estimates = study.estimates;
    benchmark::DoNotOptimize(study.solvers.data());
  }
  state.counters["estimates"] = static_cast<double>(estimates);
  state.counters["estimates_per_s"] =
      benchmark::Counter(static_cast<double>(estimates) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
}
BENCHMARK(BM_StudyRun)->Unit(benchmark::kSecond)->Iterations(3);

void BM_SqliteEstimateScan(benchmark::State& state) {
  const std::string& path = database();
  std::int64_t rows = 0;
  for (auto _ : state) {
    sqlite3* db = nullptr;
    if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY | SQLITE_OPEN_NOMUTEX, nullptr) !=
        SQLITE_OK)
      throw std::runtime_error(path + ": " + sqlite3_errmsg(db));
    sqlite3_stmt* select = nullptr;
    sqlite3_prepare_v2(db,
                       "SELECT frame_id, solver, scope, r00, r01, r02, r10, r11, r12, r20, r21, "
                       "r22, distance_m, reprojection_error_px, generalization_error_px, "
                       "converged, termination, time_us, ambiguity_ratio, tx_m, ty_m, tz_m "
                       "FROM estimates ORDER BY id",
                       -1, &select, nullptr);
    double sum = 0;
    rows = 0;
    while (sqlite3_step(select) == SQLITE_ROW) {
      for (int c : {1, 2, 16})
        sum += sqlite3_column_bytes(select, c) + (sqlite3_column_text(select, c) != nullptr);
      for (int c = 0; c < 22; ++c)
        if (c != 1 && c != 2 && c != 16) sum += sqlite3_column_double(select, c);
      ++rows;
    }
    sqlite3_finalize(select);
    sqlite3_close(db);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["rows"] = static_cast<double>(rows);
}
BENCHMARK(BM_SqliteEstimateScan)->Unit(benchmark::kSecond)->Iterations(3);

void BM_ReportWrite(benchmark::State& state) {
  const std::string& db = database();
  const std::string out = "/tmp/rig-bench-report-out-" + std::to_string(getpid());
  for (auto _ : state) {
    const db::report::Report report(db, db::report::ReportOptions{});
    report.write(out);
  }
  std::filesystem::remove_all(out);
}
BENCHMARK(BM_ReportWrite)->Unit(benchmark::kSecond)->Iterations(3);

}  // namespace

BENCHMARK_MAIN();
