#pragma once
// db::store::Store's state, shared by store_runs.cpp and store_positions.cpp (private to db).

#include <cstdint>
#include <string>
#include <utility>

#include "db/store/sqlite.hpp"

namespace db::store {

struct Store::Impl {
  Impl(const std::string& path, bool read_only);
  bool record_store_time = false;
  sqlite::Connection connection;
  // The statements of append_position, prepared once: a position of two
  // frames with every solver is about a hundred inserts.
  sqlite::Statement run_state;
  sqlite::Statement insert_position;
  sqlite::Statement insert_stage;
  sqlite::Statement insert_frame;
  sqlite::Statement insert_detection;
  sqlite::Statement insert_estimate;
  sqlite::Statement insert_bound;
  sqlite::Statement insert_visible;

  void prepare_writers();
  // The rows of one position, inside append_position's transaction; `where`
  // prefixes errors. Throws DuplicatePosition if the plan index is taken.
  // Returns the position's row id.
  std::int64_t write_rows(std::int64_t run_id, const PositionRecord& p, const std::string& where);
  // append_position, or with retake_failed retake_failed_position.
  void append(std::int64_t run_id, const PositionRecord& p, bool retake_failed);
  // status and plan_size of a run; throws StoreError naming the run if absent.
  std::pair<RunStatus, std::int64_t> run_state_of(std::int64_t run_id);
};

}  // namespace db::store
