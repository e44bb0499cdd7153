// A small RAII layer over one SQLite connection: WAL journal, busy timeout, prepared statements, and
// write transactions that always start with BEGIN IMMEDIATE (a deferred transaction that reads and then
// writes fails at once with "database is locked", whatever the timeout; PLATFORM-NOTES).
#pragma once

#include <sqlite3.h>

#include <cstdint>
#include <mutex>
#include <stdexcept>
#include <string>

namespace gonogo::cache {

class DatabaseError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Statement {
 public:
  Statement(sqlite3* db, const std::string& sql);
  ~Statement();
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  Statement& Bind(int index, int64_t value);
  Statement& Bind(int index, double value);
  Statement& Bind(int index, const std::string& text);
  Statement& BindBlob(int index, const void* data, size_t bytes);
  Statement& BindNull(int index);
  // Steps once: true when a row is available, false when done. Throws on error.
  bool Step();
  // Steps to completion (for statements that return no rows).
  void Run();

  int64_t Int(int column) const;
  double Double(int column) const;
  std::string Text(int column) const;
  std::string Blob(int column) const;
  bool IsNull(int column) const;

 private:
  sqlite3* db_;
  sqlite3_stmt* stmt_ = nullptr;
};

class Database {
 public:
  // Opens (creating if needed) the file and migrates its schema to the version this code knows.
  // Throws DatabaseError when the file is newer than the code or cannot be opened.
  explicit Database(const std::string& path);
  ~Database();
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  void Exec(const std::string& sql);
  Statement Prepare(const std::string& sql) { return Statement(db_, sql); }
  int64_t LastInsertRowId() const { return sqlite3_last_insert_rowid(db_); }
  int64_t Changes() const { return sqlite3_changes64(db_); }
  int SchemaVersion();
  const std::string& path() const { return path_; }

  // One connection is shared by the threads of rank 0; every use holds this lock.
  std::recursive_mutex& mutex() { return mutex_; }

 private:
  void Migrate();

  std::string path_;
  sqlite3* db_ = nullptr;
  std::recursive_mutex mutex_;
};

// BEGIN IMMEDIATE ... COMMIT, rolled back when the scope exits by an exception.
class WriteTransaction {
 public:
  explicit WriteTransaction(Database& db);
  ~WriteTransaction();
  void Commit();

 private:
  Database& db_;
  std::lock_guard<std::recursive_mutex> lock_;
  bool done_ = false;
};

}  // namespace gonogo::cache
