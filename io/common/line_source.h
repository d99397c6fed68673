#pragma once
// Physical lines of a text, one at a time, from memory or from a file read in blocks (never
// whole), so that a reader of a long program keeps what it parsed, not the text. Line endings as
// splitLines (io/common/text_util.h): LF, CRLF or CR; a trailing newline adds no empty line.
// A UTF-8 byte-order mark before the first line (editors on Windows write one) is dropped.
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>

namespace tolver {

class LineSource {
 public:
  // Lines of text held by the caller (it must outlive the source).
  explicit LineSource(std::string_view text);
  // Lines of a file; throws InputError(path, ...) when it cannot be opened or read.
  static LineSource file(const std::string& path);
  LineSource(LineSource&&) noexcept;
  LineSource& operator=(LineSource&&) noexcept;
  ~LineSource();

  // The next line into `line` (without its ending); false at the end of the text.
  bool next(std::string& line);
  // The text's size in bytes when known (a regular file, or text in memory), else 0: for a
  // reader that keeps the text, to reserve it at once.
  size_t sizeHint() const { return size_hint_; }
  const std::string& name() const { return name_; }
  // Bytes read so far (of a file: up to a block ahead of the lines returned), for progress.
  size_t bytesRead() const { return bytes_read_; }

 private:
  LineSource() = default;
  bool fill();  // more of the file into buf_; false at its end

  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::string name_;
  std::string buf_;        // the file's block being read
  std::string spare_;      // the next block's buffer
  std::string_view rest_;  // what is left to read: of buf_, or of the caller's text
  bool first_ = true;
  size_t size_hint_ = 0;
  size_t bytes_read_ = 0;
};

// The first `max_bytes` of a file (for guessing its dialect before it is streamed); throws
// InputError when it cannot be opened.
std::string readFilePrefix(const std::string& path, size_t max_bytes);

}  // namespace tolver
