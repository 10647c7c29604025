#include "db/store/sqlite.hpp"

#include <utility>

namespace db::store::sqlite {

Connection::Connection(const std::string& path, int flags) : path_(path) {
  const int rc = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
  if (rc != SQLITE_OK) {
    const std::string reason = db_ != nullptr ? sqlite3_errmsg(db_) : sqlite3_errstr(rc);
    sqlite3_close(db_);
    db_ = nullptr;
    throw StoreError(path + ": cannot open the database: " + reason);
  }
  sqlite3_extended_result_codes(db_, 1);
}

Connection::~Connection() {
  sqlite3_close_v2(db_);
}

void Connection::fail(int code, std::string_view what) const {
  std::string message = path_ + ": " + std::string(what) + ": " + sqlite3_errmsg(db_);
  if ((code & 0xff) == SQLITE_CONSTRAINT) throw ConstraintError(message, code);
  if ((code & 0xff) == SQLITE_BUSY) {
    message += " (another connection held the write lock for longer than busy_timeout_ms)";
  }
  throw StoreError(message);
}

void Connection::exec(std::string_view sql) {
  const std::string text(sql);
  const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) fail(rc, "executing \"" + text.substr(0, 60) + "\"");
}

Statement::Statement(Connection& connection, std::string_view sql, bool persistent)
    : connection_(&connection) {
  const int rc =
      sqlite3_prepare_v3(connection.handle(), sql.data(), static_cast<int>(sql.size()),
                         persistent ? SQLITE_PREPARE_PERSISTENT : 0, &statement_, nullptr);
  if (rc != SQLITE_OK) {
    connection.fail(rc, "preparing \"" + std::string(sql.substr(0, 60)) + "\"");
  }
}

Statement::~Statement() {
  sqlite3_finalize(statement_);
}

Statement::Statement(Statement&& other) noexcept
    : connection_(other.connection_), statement_(std::exchange(other.statement_, nullptr)) {}

Statement& Statement::operator=(Statement&& other) noexcept {
  if (this != &other) {
    sqlite3_finalize(statement_);
    connection_ = other.connection_;
    statement_ = std::exchange(other.statement_, nullptr);
  }
  return *this;
}

namespace {
void check_bind(Connection* connection, int rc) {
  if (rc != SQLITE_OK) connection->fail(rc, "binding a parameter");
}
}  // namespace

Statement& Statement::bind(int index, double value) {
  check_bind(connection_, sqlite3_bind_double(statement_, index, value));
  return *this;
}
Statement& Statement::bind(int index, std::int64_t value) {
  check_bind(connection_, sqlite3_bind_int64(statement_, index, value));
  return *this;
}
Statement& Statement::bind(int index, std::string_view text) {
  check_bind(connection_, sqlite3_bind_text64(statement_, index, text.data(), text.size(),
                                              SQLITE_TRANSIENT, SQLITE_UTF8));
  return *this;
}
Statement& Statement::bind_blob(int index, std::string_view bytes) {
  check_bind(connection_,
             sqlite3_bind_blob64(statement_, index, bytes.data(), bytes.size(), SQLITE_TRANSIENT));
  return *this;
}
Statement& Statement::bind(int index, const std::optional<double>& value) {
  if (value) return bind(index, *value);
  check_bind(connection_, sqlite3_bind_null(statement_, index));
  return *this;
}
Statement& Statement::bind(int index, const std::optional<std::int64_t>& value) {
  if (value) return bind(index, *value);
  check_bind(connection_, sqlite3_bind_null(statement_, index));
  return *this;
}
Statement& Statement::bind(int index, const std::optional<std::string>& value) {
  if (value) return bind(index, std::string_view(*value));
  check_bind(connection_, sqlite3_bind_null(statement_, index));
  return *this;
}

bool Statement::step() {
  const int rc = sqlite3_step(statement_);
  if (rc == SQLITE_ROW) return true;
  if (rc == SQLITE_DONE) return false;
  const std::string sql = sqlite3_sql(statement_);
  sqlite3_reset(statement_);
  connection_->fail(rc, "running \"" + sql.substr(0, 60) + "\"");
}

void Statement::run() {
  step();
  reset();
}

void Statement::reset() {
  sqlite3_reset(statement_);
  sqlite3_clear_bindings(statement_);
}

bool Statement::is_null(int column) const {
  return sqlite3_column_type(statement_, column) == SQLITE_NULL;
}
double Statement::get_double(int column) const {
  return sqlite3_column_double(statement_, column);
}
std::int64_t Statement::get_int64(int column) const {
  return sqlite3_column_int64(statement_, column);
}
std::string Statement::get_text(int column) const {
  const auto* text = sqlite3_column_text(statement_, column);
  const int size = sqlite3_column_bytes(statement_, column);
  return text != nullptr ? std::string(reinterpret_cast<const char*>(text), size) : std::string();
}
std::string_view Statement::get_text_view(int column) const {
  const auto* text = sqlite3_column_text(statement_, column);
  const int size = sqlite3_column_bytes(statement_, column);
  return text != nullptr ? std::string_view(reinterpret_cast<const char*>(text), size)
                         : std::string_view();
}
std::string Statement::get_blob(int column) const {
  const void* blob = sqlite3_column_blob(statement_, column);
  const int size = sqlite3_column_bytes(statement_, column);
  return blob != nullptr ? std::string(static_cast<const char*>(blob), size) : std::string();
}
std::optional<double> Statement::get_optional_double(int column) const {
  if (is_null(column)) return std::nullopt;
  return get_double(column);
}
std::optional<std::int64_t> Statement::get_optional_int64(int column) const {
  if (is_null(column)) return std::nullopt;
  return get_int64(column);
}
std::optional<std::string> Statement::get_optional_text(int column) const {
  if (is_null(column)) return std::nullopt;
  return get_text(column);
}

Transaction::Transaction(Connection& connection, Kind kind) : connection_(connection) {
  connection_.exec(kind == Kind::kWrite ? "BEGIN IMMEDIATE" : "BEGIN");
}

Transaction::~Transaction() {
  // ROLLBACK cannot usefully fail here: if it does, SQLite has already rolled
  // the transaction back (the error that got us here did), or the connection
  // is closing, which rolls back too.
  if (open_) sqlite3_exec(connection_.handle(), "ROLLBACK", nullptr, nullptr, nullptr);
}

void Transaction::commit() {
  connection_.exec("COMMIT");
  open_ = false;
}

}  // namespace db::store::sqlite
