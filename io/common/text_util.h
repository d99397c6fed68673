#pragma once
// Small text helpers shared by the readers.
#include <functional>
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
// CSV, one policy for every table tolver reads or writes (RFC 4180 quoting):
//  * a cell is trimmed; a cell in double quotes may hold commas, and "" stands for one quote;
//  * blank lines and lines starting with '#' are skipped (comments);
//  * the first other line is the header: column names, matched case-insensitively (lowercased),
//    each at most once;
//  * a written cell is quoted when it holds a comma, a quote, a line break or edge spaces.
// Splits one CSV line into its cells.
std::vector<std::string> splitCsvLine(const std::string& line);
// One cell as written: quoted and escaped when needed (see above).
std::string csvField(std::string_view cell);
// Cells joined into one CSV line (no line ending).
std::string csvLine(const std::vector<std::string>& cells);

// The header of a CSV table: its 1-based line and column name (lowercased) -> 0-based index.
struct CsvHeader {
  int line = 0;
  std::map<std::string, int> columns;
  bool has(const std::string& name) const { return columns.count(name) > 0; }
};
// One data line of a headered CSV table (forEachCsvRow).
struct CsvRow {
  int line = 0;  // 1-based line in the file
  const std::vector<std::string>* cells = nullptr;
  const std::map<std::string, int>* columns = nullptr;  // header name -> 0-based index
  // The cell under the header name, "" when the column or the cell is absent.
  std::string cell(const std::string& name) const;
  // The 1-based column of a header name, 0 when there is no such column.
  int column(const std::string& name) const;
};
// Reads a headered CSV table (see above): the header is passed to `header` (when given), every
// later line to `row`. No header line, a column named twice, or a required column missing throws
// InputError(file, header line, 0, column, missing_message for the last).
void forEachCsvRow(const std::string& text, const std::string& file,
                   const std::vector<std::string>& required, const std::string& missing_message,
                   const std::function<void(const CsvRow&)>& row,
                   const std::function<void(const CsvHeader&)>& header = {});
// Strict number: the whole (trimmed) token must be a finite decimal number ("1.", "-.5",
// "1.0E-3", "+2"); returns nullopt otherwise.
std::optional<double> parseNumber(std::string_view token);
// Formats a double with the shortest digits that read back to it (std::to_chars, no locale).
std::string formatNumber(double v);
// Formats one double by a printf format ("%+.2f", "%.4g"): the reports' fixed precisions.
std::string formatWith(const char* printf_format, double v);
// One line of numbers built in place, for the writers of one line per point (the predicted CL,
// the point table): fixed(v, n) writes the same bytes as printf's "%.<n>f" (both round exactly:
// to nearest, ties to even on the binary value), by integer digits when |v| 10^n < 2^51 and by
// std::to_chars otherwise; no allocation. Holds 48 numbers of any magnitude (330 bytes each).
class LineBuilder {
 public:
  LineBuilder& text(std::string_view s);
  LineBuilder& fixed(double v, int decimals);
  LineBuilder& general(double v, int precision);  // printf's "%.<precision>g"
  LineBuilder& integer(long long v);
  LineBuilder& character(char c);
  std::string_view view() const { return {buf_, static_cast<size_t>(at_ - buf_)}; }
  void clear() { at_ = buf_; }

 private:
  char buf_[16384];
  char* at_ = buf_;
};

// s with & < > " replaced by their XML/HTML entities.
std::string xmlEscape(std::string_view s);

// The operation a CAM comment names, or empty: "begin operation: Profile" (FreeCAD),
// "Operation : CURVE_DRIVE" (NX posts), "OPERATION=  ROUGH7  Z LEVEL ..." (Creo), "OPERATION NAME :
// Sweeping.1" (CATIA); "finish/end operation" lines name none. Inner spaces collapsed, at most 60
// characters.
std::string operationName(std::string_view comment);
// Base64 (RFC 4648, with padding) of bytes, for images embedded in HTML reports.
std::string base64Encode(const std::string& bytes);
// An HTML <img> holding a PNG file's bytes (self-contained: data URI).
std::string htmlPng(const std::string& png_bytes, const std::string& alt);

}  // namespace tolver
