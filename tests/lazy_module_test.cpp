// Modules opened on first use (core/numerics/lazy_module.h): their failures are errors that name
// what is missing.
#include "core/numerics/lazy_module.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

namespace tolver {
namespace {

// A module that is not there, or a function a module does not have: one error naming the
// module, the places tried and the function (core/numerics/lazy_module.h), never a crash.
TEST(Modules, AMissingModuleOrFunctionIsOneErrorNamingIt) {
  std::string what;
  try {
    moduleSymbol("tolver_nosuch", "render");
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("cannot load tolver's module tolver_nosuch"), std::string::npos) << what;
  EXPECT_NE(what.find("libtolver_nosuch.so"), std::string::npos) << what;
  EXPECT_NE(what.find("tried"), std::string::npos) << what;
  what.clear();
  try {
    moduleSymbol("tolver_vtk", "noSuchFunction");
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  EXPECT_NE(what.find("has no function noSuchFunction"), std::string::npos) << what;
  // The module the report uses loads, and gives the same function each time.
  EXPECT_NE(moduleSymbol("tolver_vtk", "writeScatterPng"), nullptr);
  EXPECT_EQ(moduleSymbol("tolver_vtk", "writeScatterPng"),
            moduleSymbol("tolver_vtk", "writeScatterPng"));
}

}  // namespace
}  // namespace tolver
