#pragma once
// Small text helpers shared by the readers.
#include <functional>
#include <initializer_list>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace tolver {

std::string_view trim(std::string_view s);
std::string toUpper(std::string_view s);
std::string toLower(std::string_view s);
// Splits text into lines (LF, CRLF or CR endings); a trailing newline adds no empty line.
std::vector<std::string> splitLines(const std::string& text);
// Splits one CSV line at commas (no quoting), each cell trimmed.
std::vector<std::string> splitCsvLine(const std::string& line);
// One data line of a headered CSV table (forEachCsvRow).
struct CsvRow {
  int line = 0;                                // 1-based line in the file
  const std::vector<std::string>* cells = nullptr;
  const std::map<std::string, int>* columns = nullptr;  // header name -> 0-based index
  // The cell under the header name, "" when the column or the cell is absent.
  std::string cell(const char* name) const;
  // The 1-based column of a header name, 0 when there is no such column.
  int column(const char* name) const;
};
// Reads a headered CSV table: blank lines and lines starting with '#' are skipped, the first
// other line names the columns, every later one is passed to row. A required column missing
// from the header throws InputError(file, header line, 0, column, missing_message).
void forEachCsvRow(const std::string& text, const std::string& file,
                   std::initializer_list<const char*> required, const std::string& missing_message,
                   const std::function<void(const CsvRow&)>& row);
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
