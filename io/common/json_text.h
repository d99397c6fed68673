#pragma once
// JSON reports as text: indented by 2, and any invalid UTF-8 in a string (a region name read
// from a user's file) replaced by U+FFFD instead of failing after other outputs were written.
#include <nlohmann/json.hpp>
#include <string>

namespace tolver {

inline std::string jsonText(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace tolver
