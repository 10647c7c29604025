#pragma once
// Thin RAII over the SQLite C API: a connection, prepared statements and a
// write transaction, every failure turned into db::store::StoreError naming
// the file and what was being done. Used by the store itself and by readers
// that query a run database directly in one read transaction (the report);
// the schema they query is docs/database.md.

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "db/store/store.hpp"

namespace db::store::sqlite {

class Connection;

class Statement {
 public:
  Statement() = default;
  Statement(Connection& connection, std::string_view sql, bool persistent = false);
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Parameters are 1-based, as in SQL's ?1, ?2, ...
  Statement& bind(int index, double value);
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, std::int64_t{value}); }
  Statement& bind(int index, std::string_view text);
  Statement& bind(int index, const std::string& text) {
    return bind(index, std::string_view(text));
  }
  Statement& bind(int index, const char* text) { return bind(index, std::string_view(text)); }
  Statement& bind_blob(int index, std::string_view bytes);
  Statement& bind(int index, const std::optional<double>& value);
  Statement& bind(int index, const std::optional<std::int64_t>& value);
  Statement& bind(int index, const std::optional<std::string>& value);

  // Advances; true while a row is available. Throws StoreError on failure
  // (the extended result code is kept for callers that map constraints).
  bool step();
  // Steps once, expecting no row (INSERT, UPDATE, DDL), then resets.
  void run();
  void reset();

  // Columns are 0-based.
  bool is_null(int column) const;
  double get_double(int column) const;
  std::int64_t get_int64(int column) const;
  int get_int(int column) const { return static_cast<int>(get_int64(column)); }
  std::string get_text(int column) const;
  std::string get_blob(int column) const;
  std::optional<double> get_optional_double(int column) const;
  std::optional<std::int64_t> get_optional_int64(int column) const;
  std::optional<std::string> get_optional_text(int column) const;

 private:
  Connection* connection_ = nullptr;
  sqlite3_stmt* statement_ = nullptr;
};

// Raised by Statement::step for constraint violations, so that a caller can
// tell "already there" from other failures.
class ConstraintError : public StoreError {
 public:
  ConstraintError(const std::string& message, int extended_code)
      : StoreError(message), extended_code(extended_code) {}
  int extended_code;
};

class Connection {
 public:
  Connection(const std::string& path, int flags);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  void exec(std::string_view sql);
  sqlite3* handle() { return db_; }
  const std::string& path() const { return path_; }
  std::int64_t last_insert_rowid() const { return sqlite3_last_insert_rowid(db_); }
  // Throws StoreError (ConstraintError for constraint codes) with the message
  // "<path>: <what>: <sqlite message>".
  [[noreturn]] void fail(int code, std::string_view what) const;

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
};

// BEGIN IMMEDIATE on construction (takes the write lock at once, so a
// transaction never fails half-way for lack of it), ROLLBACK on destruction
// unless commit() was called.
class Transaction {
 public:
  explicit Transaction(Connection& connection);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  void commit();

 private:
  Connection& connection_;
  bool open_ = true;
};

}  // namespace db::store::sqlite
