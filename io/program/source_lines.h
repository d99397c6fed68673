#pragma once
// The physical lines of a program file in one buffer (8 bytes a line besides the text kept), for
// the writers that copy a program's statements. A reader may leave out the text of lines no
// writer copies (the APT reader, of its GOTO and FROM statements, whose points the writers
// regenerate), so that a long program costs its points, not its text.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace tolver {

class SourceLines {
 public:
  // Room for `bytes` of text and `lines` lines (a reader that knows the file's size).
  void reserve(size_t bytes, size_t lines) {
    text_.reserve(bytes);
    end_.reserve(lines);
  }
  // Appends the next line; its text is kept only when `keep`.
  void push(std::string_view line, bool keep);
  // Lines pushed, dropped ones included (the number of the next line, 0-based).
  size_t size() const { return first_ + end_.size(); }
  bool empty() const { return size() == 0; }
  // The first line held (0-based): a program read in blocks drops the lines it passed on.
  size_t first() const { return first_; }
  void dropAll() {
    first_ += end_.size();
    text_.clear();
    end_.clear();
  }
  // Line i (0-based, first() <= i < size()): its text, or "" when it was not kept.
  std::string_view operator[](size_t i) const;
  bool kept(size_t i) const { return (end_[i - first_] & kDropped) == 0; }

 private:
  static constexpr std::uint64_t kDropped = std::uint64_t{1} << 63;
  std::string text_;
  std::vector<std::uint64_t> end_;  // per line: its end offset in text_, kDropped when not kept
  size_t first_ = 0;
};

}  // namespace tolver
