#pragma once
// Small text helpers shared by the readers.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tolver {

std::string_view trim(std::string_view s);
std::string toUpper(std::string_view s);
// Splits text into lines (LF, CRLF or CR endings); a trailing newline adds no empty line.
std::vector<std::string> splitLines(const std::string& text);
// Splits one CSV line at commas (no quoting), each cell trimmed.
std::vector<std::string> splitCsvLine(const std::string& line);
// Strict number: the whole (trimmed) token must be a finite decimal number ("1.", "-.5",
// "1.0E-3", "+2"); returns nullopt otherwise.
std::optional<double> parseNumber(std::string_view token);
// Formats a double with the shortest precision that round-trips (17 significant digits max).
std::string formatNumber(double v);
// s with & < > " replaced by their XML/HTML entities.
std::string xmlEscape(std::string_view s);
// Base64 (RFC 4648, with padding) of bytes, for images embedded in HTML reports.
std::string base64Encode(const std::string& bytes);

}  // namespace tolver
