#pragma once
// Thin RAII over the SQLite C API: a connection, prepared statements and
// transactions, every failure turned into db::store::StoreError naming the
// file and what was being done. Used by the store itself and by readers that
// query a run database directly in one read transaction (the report); the
// schema they query is docs/database.md.

#include <sqlite3.h>

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "db/store/store.hpp"

namespace db::store::sqlite {

class Connection;

// A prepared statement of one connection. Parameters are 1-based, as in
// SQL's ?1, ?2, ...; columns are 0-based. Every member that talks to SQLite
// throws StoreError (ConstraintError for a constraint violation) with the
// message "<path>: <what>: <sqlite message>".
class Statement {
 public:
  Statement() = default;
  // Prepares sql on the connection, which must outlive the statement.
  // persistent: a hint to SQLite that the statement is kept and run many
  // times. Throws StoreError naming the start of the SQL if it does not
  // prepare.
  Statement(Connection& connection, std::string_view sql, bool persistent = false);
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Binds parameter `index` (text and blobs are copied; an empty optional
  // binds NULL). Throws StoreError for an index outside the statement's
  // parameters.
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

  // Advances; true while a row is available, false when done. Throws
  // StoreError (ConstraintError for constraint codes, keeping the extended
  // result code) after resetting the statement.
  bool step();
  // Steps once, expecting no row (INSERT, UPDATE, DDL), then resets. Throws
  // as step().
  void run();
  // Back to before the first step, with every parameter unbound (NULL).
  void reset();

  // Column values of the current row. Precondition: the last step()
  // returned true. NULL reads as 0, 0.0 or "" (use is_null or the optional
  // getters to tell); values convert as SQLite converts them.
  bool is_null(int column) const;
  double get_double(int column) const;
  std::int64_t get_int64(int column) const;
  int get_int(int column) const { return static_cast<int>(get_int64(column)); }
  std::string get_text(int column) const;
  // The text without a copy: valid until the next step(), reset() or read
  // of the same column as another type.
  std::string_view get_text_view(int column) const;
  std::string get_blob(int column) const;
  // nullopt for NULL.
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
  int extended_code;  // SQLite's extended result code, e.g. SQLITE_CONSTRAINT_UNIQUE
};

// One SQLite connection, with extended result codes on; closed on
// destruction (SQLite defers the close until its statements are finalized).
class Connection {
 public:
  // Opens path with sqlite3_open_v2 flags (e.g. SQLITE_OPEN_READONLY).
  // Throws StoreError naming the file and SQLite's reason if it cannot.
  Connection(const std::string& path, int flags);
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  // Runs SQL without results (several statements allowed). Throws StoreError
  // naming the start of the SQL.
  void exec(std::string_view sql);
  sqlite3* handle() { return db_; }
  const std::string& path() const { return path_; }
  // Row id of the last successful INSERT on this connection.
  std::int64_t last_insert_rowid() const { return sqlite3_last_insert_rowid(db_); }
  // Throws StoreError (ConstraintError for constraint codes) with the message
  // "<path>: <what>: <sqlite message>".
  [[noreturn]] void fail(int code, std::string_view what) const;

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
};

// A transaction of one connection, rolled back on destruction unless
// commit() was called (a failed rollback is ignored: SQLite has then already
// rolled back, or the connection is closing, which rolls back too).
class Transaction {
 public:
  enum class Kind {
    // BEGIN IMMEDIATE: takes the write lock at once, so a transaction never
    // fails half-way for lack of it.
    kWrite,
    // BEGIN (deferred): one snapshot of the file, taken at the first read and
    // held until commit, however other connections write meanwhile.
    kRead,
  };
  // Throws StoreError if the transaction cannot begin (for kWrite, e.g.
  // another connection held the write lock beyond the busy timeout).
  explicit Transaction(Connection& connection, Kind kind = Kind::kWrite);
  ~Transaction();
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;
  // Throws StoreError if the commit fails; the transaction is then rolled
  // back on destruction.
  void commit();

 private:
  Connection& connection_;
  bool open_ = true;
};

}  // namespace db::store::sqlite
