#pragma once
// Libraries a few commands need, loaded when first used: VTK's renderer (the images), OpenCASCADE
// (STEP parts) and pagmo (NSGA-II) cost 50-70 ms each of every start of the program (their
// relocations and static constructors: 0.28 s of `tolver --version` with all three linked), so
// they live in modules, lib<name>.so, that the process opens on a first call. A module exports
// one function, `tolver_module_symbol(const char* name)`, returning its implementation of the
// function of that name (its type checked against the header's declaration in the module).
//
// A module is looked for in $TOLVER_MODULE_DIR, then beside the program's executable (in
// `modules/` and `../modules/`), then in the build tree's modules directory. Not found, or
// without the name: std::runtime_error naming the module, the places tried and dlerror().
#include <string>

namespace tolver {

void* moduleSymbol(const char* module, const char* name);

// The module's implementation of the function `name`, of the caller's type F (a function type:
// decltype of the stub's own declaration). Loaded once; later calls return the same pointer.
template <class F>
F* moduleFunction(const char* module, const char* name) {
  return reinterpret_cast<F*>(moduleSymbol(module, name));
}

}  // namespace tolver

// In a module's one exporting file: `TOLVER_MODULE_EXPORTS({"name", &impl::name}, ...)`.
#define TOLVER_MODULE_EXPORTS(...)                                                                 \
  extern "C" __attribute__((visibility("default"))) void* tolver_module_symbol(const char* name) { \
    struct Entry {                                                                                 \
      const char* name;                                                                            \
      void* function;                                                                              \
    };                                                                                             \
    static const Entry entries[] = {__VA_ARGS__};                                                  \
    for (const Entry& e : entries)                                                                 \
      if (std::string(e.name) == name) return e.function;                                          \
    return nullptr;                                                                                \
  }
