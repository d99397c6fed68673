// Modules opened on first use: see core/numerics/lazy_module.h.
#include "core/numerics/lazy_module.h"

#include <dlfcn.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace tolver {
namespace {

std::vector<std::string> moduleDirectories() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("TOLVER_MODULE_DIR"); env && *env) dirs.push_back(env);
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    dirs.push_back((exe.parent_path() / "modules").string());
    dirs.push_back((exe.parent_path().parent_path() / "modules").string());
  }
#ifdef TOLVER_BUILD_MODULE_DIR
  dirs.push_back(TOLVER_BUILD_MODULE_DIR);
#endif
  return dirs;
}

void* openModule(const char* module) {
  std::string tried, why;
  for (const std::string& dir : moduleDirectories()) {
    const std::string path = dir + "/lib" + module + ".so";
    if (!std::filesystem::exists(path)) {
      tried += (tried.empty() ? "" : ", ") + path;
      continue;
    }
    if (void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
    const char* e = dlerror();
    why = e ? e : "unknown error";
    tried += (tried.empty() ? "" : ", ") + path;
    break;
  }
  throw std::runtime_error(std::string("cannot load tolver's module ") + module + " (tried " +
                           tried + (why.empty() ? "" : "): " + why) +
                           (why.empty() ? "): install it beside the program, or set "
                                          "TOLVER_MODULE_DIR"
                                        : ""));
}

}  // namespace

void* moduleSymbol(const char* module, const char* name) {
  static std::mutex mutex;
  static std::map<std::string, void*> handles;
  std::lock_guard<std::mutex> lock(mutex);
  void*& handle = handles[module];
  if (!handle) handle = openModule(module);
  using Lookup = void*(const char*);
  auto* lookup = reinterpret_cast<Lookup*>(dlsym(handle, "tolver_module_symbol"));
  void* f = lookup ? lookup(name) : nullptr;
  if (!f)
    throw std::runtime_error(std::string("tolver's module ") + module + " has no function " + name +
                             ": it belongs to another build of tolver");
  return f;
}

}  // namespace tolver
