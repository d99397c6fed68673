#pragma once
// Errors in files and options: thrown at the io boundary, caught once by the CLI, which prints
// what() as one line and exits with code 2.
#include <cstdio>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tolver {

class InputError : public std::runtime_error {
 public:
  // file: path as given; line, column: 1-based, 0 when unknown; field: what was being read.
  InputError(const std::string& file, int line, int column, const std::string& field,
             const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }
  int column() const { return column_; }
  const std::string& field() const { return field_; }
  // The message alone, without file, line and field.
  const std::string& message() const { return message_; }

 protected:
  // An error of no file: what() is "field: message".
  InputError(const std::string& field, const std::string& message);

 private:
  std::string message_;
  std::string file_;
  int line_;
  int column_;
  std::string field_;
};

// An invalid value of a command's input that no file holds: `field` is the name of the input
// (the member of the command's Inputs struct, e.g. "tolerance_mm"), never a command-line option;
// the CLI turns it back into the option the user typed (app/common.h, optionForField).
class FieldError : public InputError {
 public:
  FieldError(const std::string& field, const std::string& message) : InputError(field, message) {}
};

// Writes content to path atomically: a temporary file beside it, then rename. Throws InputError
// (field "output") when the directory cannot be written.
void writeFileAtomically(const std::string& path, const std::string& content);

// Text written in pieces, into a string (no file) or into a file flushed every megabyte, so
// that a long output (a predicted program, its point table) never sits whole in memory.
class TextOut {
 public:
  TextOut() = default;
  explicit TextOut(std::FILE* file) : file_(file) {}
  TextOut& operator+=(std::string_view s) {
    buf_ += s;
    if (file_ && buf_.size() >= kFlushBytes) flush();
    return *this;
  }
  TextOut& operator+=(char c) { return *this += std::string_view(&c, 1); }
  // Writes what is buffered to the file; false once any write failed.
  bool flush();
  // The text, without a file.
  std::string take() { return std::move(buf_); }

 private:
  static constexpr size_t kFlushBytes = 1 << 20;
  std::FILE* file_ = nullptr;
  std::string buf_;
  bool ok_ = true;
};

// Several outputs of one command written as a set: add() writes each to a temporary file beside
// its path (returning that name, so the command can read back what it wrote); commit() renames
// them all. A failure before commit() (a second output that cannot be written) leaves none of
// the new files and every previous one in place; the destructor removes the temporaries.
class OutputSet {
 public:
  OutputSet();
  OutputSet(const OutputSet&) = delete;
  OutputSet& operator=(const OutputSet&) = delete;
  ~OutputSet();
  std::string add(const std::string& path, const std::string& content);
  // The same for a file a library writes itself (VTK, assimp): write(temporary) returns false
  // when it failed.
  std::string addWritten(const std::string& path,
                         const std::function<bool(const std::string&)>& write);
  // The same for text made in pieces (TextOut), written as it is made.
  std::string addStreamed(const std::string& path, const std::function<void(TextOut&)>& fill);
  // A file written in pieces over the command's work (a program streamed block by block): the
  // TextOut stays valid until commit(), which flushes and closes it before the renames (throwing
  // InputError when a write failed).
  TextOut& open(const std::string& path);
  // Flushes and closes the file open() opened for `path` (still renamed by commit()), so that
  // the command can read back what it wrote; returns the temporary's name. Throws InputError
  // when a write failed.
  std::string close(const std::string& path);
  void commit();

 private:
  struct Open;
  void closeAll();
  std::vector<std::pair<std::string, std::string>> pending_;  // temporary, final path
  std::vector<std::unique_ptr<Open>> open_;
};

// A report directory written as a whole: the files go to a staging directory beside it
// (`.<name>.tmp-<pid>`), and commit() swaps it in with one atomic rename (renameat2
// RENAME_EXCHANGE when the directory exists), so that a run killed while writing leaves the
// previous report as it was. A second run writing the same directory at the same time is refused
// (an flock on `.<name>.lock` beside it, released when the process ends). Throws InputError
// (field `option`) when the place cannot be written or the lock is held.
class ReportDirectory {
 public:
  explicit ReportDirectory(const std::string& dir, const char* option = "--report-dir");
  ReportDirectory(const ReportDirectory&) = delete;
  ReportDirectory& operator=(const ReportDirectory&) = delete;
  ~ReportDirectory();  // removes the staging directory unless committed
  const std::string& staging() const { return staging_; }
  const std::string& final() const { return final_; }
  void commit();

 private:
  std::string final_, staging_, option_;
  int lock_fd_ = -1;
  bool committed_ = false;
};

// Reads a whole file; throws InputError when it cannot be opened.
std::string readFile(const std::string& path);

}  // namespace tolver
