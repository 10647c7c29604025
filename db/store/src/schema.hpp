#pragma once
// Numbered migrations of the run database and the checks made when a file is
// opened (private to db).

#include "db/store/sqlite.hpp"

namespace db::store::schema {

// Checks that the open connection's file is empty or a rig run database of a
// schema this code knows (SchemaError otherwise), switches it to WAL, turns
// foreign keys on, and applies the missing migrations in one transaction.
void open_and_migrate(sqlite::Connection& connection, const StoreOptions& options);

}  // namespace db::store::schema
