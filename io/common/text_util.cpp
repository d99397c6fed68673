#include "io/common/text_util.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "io/common/io_error.h"

namespace tolver {

namespace {
// isspace in the "C" locale, without the locale's table lookup.
inline bool space(char c) { return c == ' ' || (c >= '\t' && c <= '\r'); }
}  // namespace

std::string_view trim(std::string_view s) {
  size_t b = 0, e = s.size();
  while (b < e && space(s[b])) ++b;
  while (e > b && space(s[e - 1])) --e;
  return s.substr(b, e - b);
}

std::string toUpper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

std::string toLower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::vector<std::string> splitLines(const std::string& text) {
  std::vector<std::string> lines;
  std::string cur;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\n' || c == '\r') {
      lines.push_back(cur);
      cur.clear();
      if (c == '\r' && i + 1 < text.size() && text[i + 1] == '\n') ++i;
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) lines.push_back(cur);
  return lines;
}

std::vector<std::string> splitCsvLine(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  bool quoted = false;      // inside a quoted cell
  bool was_quoted = false;  // the current cell was quoted: keep its inner spaces
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cur += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cur += c;
      }
    } else if (c == '"' && trim(cur).empty()) {
      cur.clear();
      quoted = was_quoted = true;
    } else if (c == ',') {
      out.emplace_back(was_quoted ? cur : std::string(trim(cur)));
      cur.clear();
      was_quoted = false;
    } else if (!(was_quoted && (c == ' ' || c == '\t'))) {
      cur += c;
    }
  }
  out.emplace_back(was_quoted ? cur : std::string(trim(cur)));
  return out;
}

std::string csvField(std::string_view cell) {
  const bool edge_space = !cell.empty() && (cell.front() == ' ' || cell.back() == ' ' ||
                                            cell.front() == '\t' || cell.back() == '\t');
  if (cell.find_first_of(",\"\r\n") == std::string_view::npos && !edge_space)
    return std::string(cell);
  std::string out = "\"";
  for (char c : cell) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

std::string csvLine(const std::vector<std::string>& cells) {
  std::string out;
  for (size_t k = 0; k < cells.size(); ++k) out += (k ? "," : "") + csvField(cells[k]);
  return out;
}

namespace {
// The common token, [+-]digits[.digits] with at most 19 digits whose integer m is below 2^53,
// at most 22 after the point: m / 10^d is one correctly rounded division of two exact doubles
// (Clinger's fast path), the value strtod and std::from_chars give. False for anything else.
bool plainDecimal(std::string_view t, double* v) {
  static constexpr double kPow10[23] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                        1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  size_t i = 0;
  const bool negative = t[0] == '-';
  if (t[0] == '-' || t[0] == '+') ++i;
  std::uint64_t m = 0;
  int digits = 0, decimals = -1;
  for (; i < t.size(); ++i) {
    const char c = t[i];
    if (c >= '0' && c <= '9') {
      if (++digits > 19) return false;
      m = m * 10 + static_cast<std::uint64_t>(c - '0');
      if (decimals >= 0) ++decimals;
    } else if (c == '.' && decimals < 0) {
      decimals = 0;
    } else {
      return false;
    }
  }
  if (digits == 0 || decimals > 22 || m > (std::uint64_t{1} << 53)) return false;
  const double x = static_cast<double>(m) / kPow10[decimals < 0 ? 0 : decimals];
  *v = negative ? -x : x;
  return true;
}
}  // namespace

std::optional<double> parseNumber(std::string_view token) {
  token = trim(token);
  if (token.empty()) return std::nullopt;
  if (double v; plainDecimal(token, &v)) return v;
  // Only digits, one dot, sign, exponent: reject hex, inf, nan and the like.
  bool digit = false;
  for (char c : token) {
    if (std::isdigit(static_cast<unsigned char>(c))) {
      digit = true;
    } else if (!(c == '.' || c == '+' || c == '-' || c == 'e' || c == 'E')) {
      return std::nullopt;
    }
  }
  if (!digit) return std::nullopt;
  // std::from_chars: correctly rounded as strtod, without a copy or the locale; it takes no '+'.
  const std::string_view body = token[0] == '+' ? token.substr(1) : token;
  if (body.size() < token.size() && (body.empty() || body[0] == '+' || body[0] == '-'))
    return std::nullopt;
  double v = 0.0;
  const auto r = std::from_chars(body.data(), body.data() + body.size(), v);
  if (r.ptr != body.data() + body.size()) return std::nullopt;
  if (r.ec == std::errc::result_out_of_range) {
    // Beyond a double (refused) or below its smallest (strtod's rounding to 0 or a subnormal).
    const std::string s(body);
    v = std::strtod(s.c_str(), nullptr);
  } else if (r.ec != std::errc()) {
    return std::nullopt;
  }
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

LineBuilder& LineBuilder::text(std::string_view s) {
  const size_t n = std::min(s.size(), static_cast<size_t>(buf_ + sizeof buf_ - at_));
  std::memcpy(at_, s.data(), n);
  at_ += n;
  return *this;
}

namespace {

// |v| 10^d rounded to an integer as printf rounds the exact binary value (to nearest, ties to
// even), when |v| 10^d < 2^51 and d <= 15; false otherwise. The product's rounding error is exact
// (Dekker's two-product, no fused multiply-add needed): a * p = y + r, |r| <= ulp(y) / 2. With
// f = floor(y), y - f is exact and a multiple of ulp(y), as is 0.5 (ulp(y) <= 2^-2 below 2^51),
// so (y - f) - 0.5 is zero or at least ulp(y) > |r| in size: r decides only an exact half.
bool scaledRound(double a, int d, std::uint64_t* n) {
  static constexpr double kPow10[16] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
  if (d < 0 || d > 15) return false;
  const double p = kPow10[d];
  const double y = a * p;
  if (!(y < 2251799813685248.0)) return false;  // 2^51; also NaN and infinities
  if (y < 0.25) {  // rounds to 0 whatever the error (and tiny a, whose split would underflow)
    *n = 0;
    return true;
  }
  std::uint64_t k = static_cast<std::uint64_t>(y);  // floor (y >= 0)
  const double h = (y - static_cast<double>(k)) - 0.5;
  if (h != 0.0) {  // the rounded product decides (above)
    *n = k + (h > 0.0 ? 1 : 0);
    return true;
  }
  // A half in the rounded product: the product's rounding error decides, and an exact half goes
  // to the even neighbour.
  auto split = [](double x, double* hi, double* lo) {
    const double c = 134217729.0 * x;  // 2^27 + 1
    *hi = c - (c - x);
    *lo = x - *hi;
  };
  double ah, al, ph, pl;
  split(a, &ah, &al);
  split(p, &ph, &pl);
  const double r = ((ah * ph - y) + ah * pl + al * ph) + al * pl;
  if (r > 0.0 || (r == 0.0 && (k & 1) != 0)) ++k;
  *n = k;
  return true;
}

}  // namespace

namespace {
// The digits of k with `decimals` after the point, at least one before, ending at `end`, written
// from the right two at a time; returns where they start. UInt: 32-bit arithmetic where k fits.
template <class UInt>
char* digitsBefore(char* end, UInt k, int decimals, int digits) {
  static constexpr char kPairs[] =
      "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
      "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
      "8081828384858687888990919293949596979899";
  char* p = end;
  int left = decimals;
  for (; left >= 2; left -= 2) {
    const UInt pair = k % 100;
    k /= 100;
    p -= 2;
    p[0] = kPairs[2 * pair];
    p[1] = kPairs[2 * pair + 1];
  }
  if (left == 1) {
    *--p = static_cast<char>('0' + k % 10);
    k /= 10;
  }
  if (decimals > 0) *--p = '.';
  char* const start = end - digits - (decimals > 0 ? 1 : 0);
  while (p - start >= 2) {
    const UInt pair = k % 100;
    k /= 100;
    p -= 2;
    p[0] = kPairs[2 * pair];
    p[1] = kPairs[2 * pair + 1];
  }
  if (p > start) *--p = static_cast<char>('0' + k);
  return p;
}
}  // namespace

LineBuilder& LineBuilder::fixed(double v, int decimals) {
  std::uint64_t k;
  // The common case (a coordinate, a deviation) by integer digits, written in place from the
  // right two at a time (in 32-bit arithmetic when k fits); any other by std::to_chars.
  if (buf_ + sizeof buf_ - at_ >= 40 && scaledRound(std::abs(v), decimals, &k)) {
    static constexpr std::uint64_t kPow10[17] = {1,
                                                 10,
                                                 100,
                                                 1000,
                                                 10000,
                                                 100000,
                                                 1000000,
                                                 10000000,
                                                 100000000,
                                                 1000000000,
                                                 10000000000,
                                                 100000000000,
                                                 1000000000000,
                                                 10000000000000,
                                                 100000000000000,
                                                 1000000000000000,
                                                 10000000000000000};
    int digits = decimals + 1;  // of k, at least one before the point
    while (digits < 16 && k >= kPow10[digits]) ++digits;
    if (std::signbit(v)) *at_++ = '-';
    char* const end = at_ + digits + (decimals > 0 ? 1 : 0);
    if (k <= 0xFFFFFFFFu)
      digitsBefore(end, static_cast<std::uint32_t>(k), decimals, digits);
    else
      digitsBefore(end, k, decimals, digits);
    at_ = end;
    return *this;
  }
  const auto r = std::to_chars(at_, buf_ + sizeof buf_, v, std::chars_format::fixed, decimals);
  if (r.ec == std::errc()) at_ = r.ptr;
  return *this;
}

LineBuilder& LineBuilder::general(double v, int precision) {
  const auto r = std::to_chars(at_, buf_ + sizeof buf_, v, std::chars_format::general, precision);
  if (r.ec == std::errc()) at_ = r.ptr;
  return *this;
}

LineBuilder& LineBuilder::integer(long long v) {
  const auto r = std::to_chars(at_, buf_ + sizeof buf_, v);
  if (r.ec == std::errc()) at_ = r.ptr;
  return *this;
}

LineBuilder& LineBuilder::character(char c) {
  if (at_ < buf_ + sizeof buf_) *at_++ = c;
  return *this;
}

std::string formatNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest that round-trips, no locale
  return std::string(buf, r.ptr);
}

std::string xmlEscape(std::string_view s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

std::string base64Encode(const std::string& in) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(in[i]) << 16) |
                       (static_cast<unsigned char>(in[i + 1]) << 8) |
                       static_cast<unsigned char>(in[i + 2]);
    out += k[v >> 18];
    out += k[(v >> 12) & 63];
    out += k[(v >> 6) & 63];
    out += k[v & 63];
  }
  if (i < in.size()) {
    unsigned v = static_cast<unsigned char>(in[i]) << 16;
    if (i + 1 < in.size()) v |= static_cast<unsigned char>(in[i + 1]) << 8;
    out += k[v >> 18];
    out += k[(v >> 12) & 63];
    out += i + 1 < in.size() ? k[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

std::string CsvRow::cell(const std::string& name) const {
  const auto it = columns->find(name);
  if (it == columns->end() || it->second >= static_cast<int>(cells->size())) return "";
  return (*cells)[it->second];
}

int CsvRow::column(const std::string& name) const {
  const auto it = columns->find(name);
  return it == columns->end() ? 0 : it->second + 1;
}

void forEachCsvRow(const std::string& text, const std::string& file,
                   const std::vector<std::string>& required, const std::string& missing_message,
                   const std::function<void(const CsvRow&)>& row,
                   const std::function<void(const CsvHeader&)>& header) {
  const auto lines = splitLines(text);
  CsvHeader h;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string_view t = trim(lines[i]);
    if (t.empty() || t[0] == '#') continue;
    const int line = static_cast<int>(i) + 1;
    // A UTF-8 byte-order mark before the first line (as spreadsheets write it) is not text.
    std::string_view raw = lines[i];
    if (h.line == 0 && raw.substr(0, 3) == "\xEF\xBB\xBF") raw.remove_prefix(3);
    const auto cells = splitCsvLine(std::string(raw));
    if (h.line == 0) {
      h.line = line;
      for (size_t k = 0; k < cells.size(); ++k) {
        const std::string name = toLower(cells[k]);
        if (h.columns.count(name))
          throw InputError(file, line, static_cast<int>(k) + 1, name, "column named twice");
        h.columns[name] = static_cast<int>(k);
      }
      for (const std::string& r : required)
        if (!h.columns.count(r)) throw InputError(file, line, 0, r, missing_message);
      if (header) header(h);
      continue;
    }
    // A row with more cells than the header has columns: the cells beyond have no name (a
    // shifted row, a comma in a value); refused unless empty (a trailing comma).
    for (size_t k = h.columns.size(); k < cells.size(); ++k)
      if (!trim(cells[k]).empty())
        throw InputError(file, line, static_cast<int>(k) + 1, "cells",
                         "the row has " + std::to_string(cells.size()) + " cells, the header " +
                             std::to_string(h.columns.size()) + " columns");
    row(CsvRow{line, &cells, &h.columns});
  }
  if (h.line == 0) throw InputError(file, 0, 0, "", "empty file: no header line");
}

std::string formatWith(const char* printf_format, double v) {
  char buf[128];
  std::snprintf(buf, sizeof buf, printf_format, v);
  return buf;
}

std::string htmlPng(const std::string& png_bytes, const std::string& alt) {
  return "<img alt=\"" + xmlEscape(alt) + "\" src=\"data:image/png;base64," +
         base64Encode(png_bytes) + "\">";
}

std::string operationName(std::string_view comment) {
  const std::string u = toUpper(comment);
  const size_t at = u.find("OPERATION");
  if (at == std::string::npos) return "";
  const std::string_view before = trim(std::string_view(u).substr(0, at));
  if (before.size() >= 3 && (before.substr(before.size() - 3) == "END" ||
                             (before.size() >= 6 && before.substr(before.size() - 6) == "FINISH")))
    return "";
  size_t k = at + 9;
  while (k < u.size() && u[k] == ' ') ++k;
  if (u.compare(k, 4, "NAME") == 0) k += 4;
  while (k < u.size() && u[k] == ' ') ++k;
  if (k >= u.size() || (u[k] != ':' && u[k] != '=')) return "";
  ++k;
  std::string name;
  for (; k < comment.size(); ++k) {
    const char c = comment[k];
    if (c == ')' || c == '\r' || c == '\n') break;
    if (std::isspace(static_cast<unsigned char>(c))) {
      if (!name.empty() && name.back() != ' ') name += ' ';
    } else {
      name += c;
    }
  }
  while (!name.empty() && name.back() == ' ') name.pop_back();
  if (name.size() > 60) name = name.substr(0, 57) + "...";
  return name;
}

}  // namespace tolver
