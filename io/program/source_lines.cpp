#include "io/program/source_lines.h"

#include <cassert>

namespace tolver {

void SourceLines::push(std::string_view line, bool keep) {
  if (keep) text_.append(line);
  end_.push_back(text_.size() | (keep ? 0 : kDropped));
}

std::string_view SourceLines::operator[](size_t i) const {
  assert(i >= first_ && i < size());
  if (!kept(i)) return {};
  i -= first_;
  const size_t begin = i == 0 ? 0 : static_cast<size_t>(end_[i - 1] & ~kDropped);
  return std::string_view(text_).substr(begin, static_cast<size_t>(end_[i]) - begin);
}

}  // namespace tolver
