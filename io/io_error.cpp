#include "io/io_error.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

namespace tolver {
namespace {
// A message quotes at most 60 characters of an offending token (the text between single
// quotes: a 3 MB line must not become a 3 MB message), and the whole stays under 2000.
std::string bounded(const std::string& text) {
  std::string out;
  bool quoted = false;
  size_t run = 0;
  for (char c : text) {
    if (c == '\'') {
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
      file_(file),
      line_(line),
      column_(column),
      field_(field) {}

namespace {
void writeTemporary(const std::string& path, const std::string& tmp, const std::string& content) {
  std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
  if (!out) throw InputError(path, 0, 0, "output", std::string("cannot write: ") + std::strerror(errno));
  out << content;
  out.flush();
  if (!out) {
    out.close();
    std::remove(tmp.c_str());
    throw InputError(path, 0, 0, "output", "write failed");
  }
}
}  // namespace

OutputSet::~OutputSet() {
  for (const auto& [tmp, path] : pending_) std::remove(tmp.c_str());
}

std::string OutputSet::add(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp-tolver";
  writeTemporary(path, tmp, content);
  pending_.emplace_back(tmp, path);
  return tmp;
}

void OutputSet::commit() {
  for (const auto& [tmp, path] : pending_)
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      throw InputError(path, 0, 0, "output", "cannot replace file: " + why);
    }
  pending_.clear();
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".tmp-tolver";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, 0, 0, "output", std::string("cannot write: ") + std::strerror(errno));
    out << content;
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw InputError(path, 0, 0, "output", "write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    std::remove(tmp.c_str());
    throw InputError(path, 0, 0, "output", "cannot replace file: " + why);
  }
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace tolver
