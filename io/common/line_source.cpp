#include "io/common/line_source.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "io/common/io_error.h"

namespace tolver {

namespace {
constexpr size_t kBlockBytes = size_t{1} << 16;

std::unique_ptr<std::FILE, void (*)(std::FILE*)> openOrThrow(const std::string& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr)
    throw InputError(path, 0, 0, "", std::string("cannot open: ") + std::strerror(errno));
  return {f, [](std::FILE* g) { std::fclose(g); }};
}
}  // namespace

LineSource::LineSource(std::string_view text)
    : rest_(text), size_hint_(text.size()), bytes_read_(text.size()) {}

LineSource LineSource::file(const std::string& path) {
  LineSource s;
  auto f = openOrThrow(path);
  s.file_.reset(f.release());
  s.name_ = path;
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (!ec) s.size_hint_ = static_cast<size_t>(size);
  return s;
}

LineSource::LineSource(LineSource&&) noexcept = default;
LineSource& LineSource::operator=(LineSource&&) noexcept = default;
LineSource::~LineSource() = default;

bool LineSource::fill() {
  if (!file_) return false;
  // Keep what is left (a line cut by the block's end) and append the next block, in the spare
  // buffer (the two swap: no allocation, no fresh pages, once they hold a block).
  // The block grows with a long line, so that reading one is linear in its length.
  std::string& next = spare_;
  next.assign(rest_);
  const size_t old = next.size();
  const size_t want = std::max(kBlockBytes, old);
  next.resize(old + want);
  const size_t got = std::fread(next.data() + old, 1, want, file_.get());
  if (got == 0 && std::ferror(file_.get()))
    throw InputError(name_, 0, 0, "", std::string("cannot read: ") + std::strerror(errno));
  next.resize(old + got);
  bytes_read_ += got;
  buf_.swap(next);
  rest_ = buf_;
  if (got == 0) file_.reset();
  return got > 0;
}

bool LineSource::next(std::string& line) {
  line.clear();
  while (true) {
    if (first_) {
      // The byte-order mark can only be judged with three bytes in hand.
      while (rest_.size() < 3 && fill()) {
      }
      if (rest_.substr(0, 3) == "\xEF\xBB\xBF") rest_.remove_prefix(3);
      first_ = false;
    }
    // The first CR or LF (two memchr: find_first_of calls one per character; none on an empty
    // view, whose data() may be null).
    size_t end = std::string_view::npos;
    if (!rest_.empty()) {
      if (const void* lf = std::memchr(rest_.data(), '\n', rest_.size()))
        end = static_cast<size_t>(static_cast<const char*>(lf) - rest_.data());
      const size_t before = end == std::string_view::npos ? rest_.size() : end;
      if (const void* cr = before > 0 ? std::memchr(rest_.data(), '\r', before) : nullptr)
        end = static_cast<size_t>(static_cast<const char*>(cr) - rest_.data());
    }
    if (end == std::string_view::npos) {
      if (fill()) continue;
      if (rest_.empty()) return false;  // the end; a last line without ending was returned
      line.assign(rest_);
      rest_ = {};
      return true;
    }
    // A CR at the block's end may be the first half of CRLF.
    if (rest_[end] == '\r' && end + 1 == rest_.size() && fill()) continue;
    line.assign(rest_.substr(0, end));
    size_t skip = end + 1;
    if (rest_[end] == '\r' && skip < rest_.size() && rest_[skip] == '\n') ++skip;
    rest_.remove_prefix(skip);
    return true;
  }
}

std::string readFilePrefix(const std::string& path, size_t max_bytes) {
  auto f = openOrThrow(path);
  std::string text(max_bytes, '\0');
  text.resize(std::fread(text.data(), 1, max_bytes, f.get()));
  return text;
}

}  // namespace tolver
