#pragma once
// Work that a library may abort on a damaged file (assimp on scene files, OpenCASCADE on STEP),
// run in a child process: the child sends its result, or the InputError it threw, through a
// pipe; a child that ends any other way (a signal, a sanitizer's exit) becomes an InputError
// "<who> stopped ... reading it: a damaged file?", and tolver goes on.
#include <functional>
#include <string>

namespace tolver {

// Runs work() in a forked child and returns the bytes it returned. Throws InputError(path, ...)
// with the child's own error (file, field and message kept), or naming `who` when the child did
// not end cleanly. in_process: run work() here instead (the fuzz harnesses, which must see what
// the library does); also when the system cannot fork.
std::string runInChildProcess(const std::string& path, const std::string& who,
                              const std::function<std::string()>& work, bool in_process = false);

// Appending and taking plain values and strings of a byte buffer (the child's result).
class ByteWriter {
 public:
  template <class T>
  void put(const T& v) {
    bytes_.append(reinterpret_cast<const char*>(&v), sizeof v);
  }
  void putBytes(const void* p, size_t n) { bytes_.append(static_cast<const char*>(p), n); }
  void putString(const std::string& s) {
    put<uint64_t>(s.size());
    bytes_ += s;
  }
  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
};

class ByteReader {
 public:
  explicit ByteReader(const std::string& bytes) : bytes_(bytes) {}
  template <class T>
  bool take(T* v) {
    return takeBytes(v, sizeof *v);
  }
  bool takeBytes(void* p, size_t n);
  bool takeString(std::string* s);
  // A count that the remaining bytes can hold at `each` bytes an element (a damaged buffer
  // never makes a huge allocation).
  bool takeCount(uint64_t* n, size_t each);

 private:
  const std::string& bytes_;
  size_t at_ = 0;
};

}  // namespace tolver
