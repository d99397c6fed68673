#include "io/common/io_error.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2, RENAME_EXCHANGE (glibc 2.28)
#include <sys/file.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tolver {
namespace {
// A message quotes at most 60 characters of an offending token (the text between single
// quotes: a 3 MB line must not become a 3 MB message), and the whole stays under 2000.
std::string bounded(const std::string& text) {
  std::string out;
  bool quoted = false;
  size_t run = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    // An apostrophe inside a word ("the program's") does not open a quotation.
    const bool in_word = !quoted && i > 0 && i + 1 < text.size() &&
                         std::isalnum(static_cast<unsigned char>(text[i - 1])) &&
                         std::isalpha(static_cast<unsigned char>(text[i + 1]));
    if (c == '\'' && !in_word) {
      quoted = !quoted;
      run = 0;
      out += c;
      continue;
    }
    if (quoted && ++run > 60) {
      if (run == 61) out += "...";
      continue;
    }
    out += c;
    if (out.size() >= 2000) {
      out += "...";
      break;
    }
  }
  return out;
}

std::string format(const std::string& file, int line, int column, const std::string& field,
                   const std::string& message) {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line);
  if (column > 0) s += ":" + std::to_string(column);
  s += ": ";
  if (!field.empty()) s += bounded(field) + ": ";
  return s + bounded(message);
}
}  // namespace

InputError::InputError(const std::string& file, int line, int column, const std::string& field,
                       const std::string& message)
    : std::runtime_error(format(file, line, column, field, message)),
      message_(bounded(message)),
      file_(file),
      line_(line),
      column_(column),
      field_(field) {}

InputError::InputError(const std::string& field, const std::string& message)
    : std::runtime_error(bounded(field) + ": " + bounded(message)),
      message_(bounded(message)),
      line_(0),
      column_(0),
      field_(field) {}

namespace {
void writeTemporary(const std::string& path, const std::string& tmp, const std::string& content) {
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out)
    throw InputError(path, 0, 0, "output", std::string("cannot write: ") + std::strerror(errno));
  out << content;
  out.flush();
  if (!out) {
    out.close();
    std::remove(tmp.c_str());
    throw InputError(path, 0, 0, "output", "write failed");
  }
}
}  // namespace

struct OutputSet::Open {
  std::string path;
  std::FILE* file = nullptr;
  TextOut out;
};

OutputSet::OutputSet() = default;

void OutputSet::closeAll() {
  std::string failed;
  for (const std::unique_ptr<Open>& o : open_) {
    const bool ok = o->out.flush();
    if (std::fclose(o->file) != 0 || !ok) failed = o->path;
  }
  open_.clear();
  if (!failed.empty()) throw InputError(failed, 0, 0, "output", "cannot write the file");
}

OutputSet::~OutputSet() {
  for (const std::unique_ptr<Open>& o : open_) std::fclose(o->file);
  for (const auto& [tmp, path] : pending_) std::remove(tmp.c_str());
}

TextOut& OutputSet::open(const std::string& path) {
  const std::string tmp = path + ".tmp-tolver";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f)
    throw InputError(path, 0, 0, "output", std::string("cannot write: ") + std::strerror(errno));
  pending_.emplace_back(tmp, path);
  open_.push_back(std::make_unique<Open>());
  open_.back()->path = path;
  open_.back()->file = f;
  open_.back()->out = TextOut(f);
  return open_.back()->out;
}

std::string OutputSet::close(const std::string& path) {
  for (auto it = open_.begin(); it != open_.end(); ++it) {
    if ((*it)->path != path) continue;
    const bool ok = (*it)->out.flush();
    const bool closed = std::fclose((*it)->file) == 0;
    open_.erase(it);
    if (!ok || !closed) throw InputError(path, 0, 0, "output", "cannot write the file");
    return path + ".tmp-tolver";
  }
  throw std::logic_error("OutputSet::close: " + path + " is not open");
}

std::string OutputSet::add(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp-tolver";
  writeTemporary(path, tmp, content);
  pending_.emplace_back(tmp, path);
  return tmp;
}

void OutputSet::commit() {
  closeAll();
  for (const auto& [tmp, path] : pending_)
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      throw InputError(path, 0, 0, "output", "cannot replace file: " + why);
    }
  pending_.clear();
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  OutputSet one;
  one.add(path, content);
  one.commit();
}

std::string OutputSet::addWritten(const std::string& path,
                                  const std::function<bool(const std::string&)>& write) {
  const std::string tmp = path + ".tmp-tolver";
  pending_.emplace_back(tmp, path);  // removed by the destructor if anything below fails
  if (!write(tmp)) throw InputError(path, 0, 0, "output", "cannot write the file");
  return tmp;
}

bool TextOut::flush() {
  if (file_ && !buf_.empty()) {
    ok_ = ok_ && std::fwrite(buf_.data(), 1, buf_.size(), file_) == buf_.size();
    buf_.clear();
  }
  return ok_;
}

std::string OutputSet::addStreamed(const std::string& path,
                                   const std::function<void(TextOut&)>& fill) {
  return addWritten(path, [&](const std::string& tmp) {
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) return false;
    TextOut out(f);
    fill(out);
    const bool ok = out.flush();
    return std::fclose(f) == 0 && ok;
  });
}

std::string readFile(const std::string& path) {
  // Read in one piece into a string of the file's size (a stream copy would hold it twice).
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) throw InputError(path, 0, 0, "", std::string("cannot open: ") + std::strerror(errno));
  const std::streamoff size = in.tellg();
  std::string text;
  if (size > 0) {
    text.resize(static_cast<size_t>(size));
    in.seekg(0);
    in.read(text.data(), size);
    text.resize(static_cast<size_t>(in.gcount()));
  } else {  // not a regular file (a pipe): read to the end
    in.clear();
    in.seekg(0);
    std::ostringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  return text;
}

ReportDirectory::ReportDirectory(const std::string& dir, const char* option) : option_(option) {
  namespace fs = std::filesystem;
  fs::path final_path = fs::path(dir).lexically_normal();
  if (final_path.filename().empty()) final_path = final_path.parent_path();
  final_ = final_path.string();
  const fs::path parent = final_path.has_parent_path() ? final_path.parent_path() : fs::path(".");
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec || !fs::is_directory(parent, ec))
    throw InputError(dir, 0, 0, option_,
                     "cannot create the directory" + (ec ? ": " + ec.message() : std::string()));
  if (fs::exists(final_path, ec) && !fs::is_directory(final_path, ec))
    throw InputError(dir, 0, 0, option_, "names a file, not a directory");
  const std::string name = final_path.filename().string();
  const std::string lock = (parent / ("." + name + ".lock")).string();
  lock_fd_ = ::open(lock.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock_fd_ < 0)
    throw InputError(dir, 0, 0, option_,
                     std::string("cannot write beside it: ") + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw InputError(
        dir, 0, 0, option_,
        "another tolver run is writing this report directory now; wait for it or give another");
  }
  // Staging directories a killed run left behind (the lock is ours: nobody is writing them).
  const std::string stale = "." + name + ".tmp-";
  for (const auto& e : fs::directory_iterator(parent, ec))
    if (e.path().filename().string().rfind(stale, 0) == 0) fs::remove_all(e.path(), ec);
  staging_ = (parent / ("." + name + ".tmp-" + std::to_string(::getpid()))).string();
  fs::remove_all(staging_, ec);
  fs::create_directories(staging_, ec);
  if (ec) throw InputError(dir, 0, 0, option_, "cannot create the directory: " + ec.message());
}

void ReportDirectory::commit() {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(final_, ec)) {
    // Swap the new report in with one atomic step; the old one is then at the staging name.
    if (::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, final_.c_str(), RENAME_EXCHANGE) != 0)
      throw InputError(final_, 0, 0, option_,
                       std::string("cannot replace the directory: ") + std::strerror(errno));
    fs::remove_all(staging_, ec);
  } else if (::rename(staging_.c_str(), final_.c_str()) != 0) {
    throw InputError(final_, 0, 0, option_,
                     std::string("cannot create the directory: ") + std::strerror(errno));
  }
  committed_ = true;
}

ReportDirectory::~ReportDirectory() {
  std::error_code ec;
  if (!committed_ && !staging_.empty()) std::filesystem::remove_all(staging_, ec);
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

}  // namespace tolver
