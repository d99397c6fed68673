#include "io/program/measured_points.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "io/common/io_error.h"
#include "io/common/text_util.h"

namespace tolver {
namespace {

constexpr double kLimit = 1e6;  // mm: a coordinate beyond 1 km is not a part's

std::vector<std::string> splitNumbers(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (c == ',' || c == ';' || c == ' ' || c == '\t') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

bool numericLine(const std::string& line) {
  const std::vector<std::string> cells = splitNumbers(line);
  if (cells.size() < 3) return false;
  for (const std::string& c : cells)
    if (!parseNumber(c)) return false;
  return true;
}

void checkNormal(MeasuredPoint& p, const std::string& file, int column) {
  const double len = p.n.norm();
  if (!(len > 1e-9))
    throw InputError(file, p.line, column, "nx", "the normal is zero: give a direction or none");
  p.n /= len;
}

std::vector<MeasuredPoint> parseAsc(const std::vector<std::string>& lines,
                                    const std::string& file) {
  std::vector<MeasuredPoint> out;
  size_t columns = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string_view t = trim(lines[i]);
    if (t.empty() || t[0] == '#' || t[0] == '/') continue;
    const std::vector<std::string> cells = splitNumbers(std::string(t));
    const int line = static_cast<int>(i) + 1;
    if (columns == 0) columns = cells.size();
    if (cells.size() != columns)
      throw InputError(file, line, 0, "x",
                       "expected " + std::to_string(columns) +
                           " numbers as on the first line, got " + std::to_string(cells.size()));
    MeasuredPoint p;
    p.line = line;
    double v[6] = {0, 0, 0, 0, 0, 0};
    for (size_t k = 0; k < cells.size() && k < 6; ++k) {
      static const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
      const auto x = parseNumber(cells[k]);
      if (!x)
        throw InputError(file, line, static_cast<int>(k) + 1, names[k],
                         "'" + cells[k] + "' is not a number");
      if (!(std::abs(*x) <= kLimit))
        throw InputError(file, line, static_cast<int>(k) + 1, names[k],
                         "'" + cells[k] + "' is out of range (within 1e6 mm)");
      v[k] = *x;
    }
    p.p = Eigen::Vector3d(v[0], v[1], v[2]);
    if (cells.size() >= 6) {
      p.n = Eigen::Vector3d(v[3], v[4], v[5]);
      checkNormal(p, file, 4);
    }
    out.push_back(p);
  }
  return out;
}

}  // namespace

namespace {

// A binary PLY value of type T from its bytes in host order.
template <typename T>
double loadAs(const unsigned char* b) {
  T v;
  std::memcpy(&v, b, sizeof v);
  return static_cast<double>(v);
}

// A PLY point cloud: the vertex element's x, y, z (and nx, ny, nz when all three are there),
// ascii or binary of either byte order; other elements after the vertices are ignored, before
// them only when they have no list properties. Every count is checked against the file's size
// before anything is allocated.
std::vector<MeasuredPoint> parsePly(const std::string& text, const std::string& file) {
  struct Property {
    std::string name;
    int size = 0;     // bytes; 0: a list
    char kind = 'f';  // 'i' signed, 'u' unsigned, 'f' floating
  };
  struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> props;
  };
  auto typeOf = [&](const std::string& t, int line) -> std::pair<int, char> {
    static const std::pair<const char*, std::pair<int, char>> types[] = {
        {"char", {1, 'i'}},  {"int8", {1, 'i'}},    {"uchar", {1, 'u'}},  {"uint8", {1, 'u'}},
        {"short", {2, 'i'}}, {"int16", {2, 'i'}},   {"ushort", {2, 'u'}}, {"uint16", {2, 'u'}},
        {"int", {4, 'i'}},   {"int32", {4, 'i'}},   {"uint", {4, 'u'}},   {"uint32", {4, 'u'}},
        {"float", {4, 'f'}}, {"float32", {4, 'f'}}, {"double", {8, 'f'}}, {"float64", {8, 'f'}}};
    for (const auto& [name, v] : types)
      if (t == name) return v;
    throw InputError(file, line, 0, "property", "unknown PLY type '" + t + "'");
  };
  std::vector<Element> elements;
  std::string format;
  size_t pos = 0;
  int line = 0;
  bool ended = false;
  while (pos < text.size() && !ended) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    std::string l = text.substr(pos, eol - pos);
    if (!l.empty() && l.back() == '\r') l.pop_back();
    pos = eol + 1;
    ++line;
    std::istringstream ss(l);
    std::string word;
    ss >> word;
    if (line == 1) {
      if (word != "ply") throw InputError(file, 1, 1, "ply", "not a PLY file");
    } else if (word == "format") {
      ss >> format;
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        throw InputError(file, line, 8, "format", "unknown PLY format '" + format + "'");
    } else if (word == "element") {
      Element e;
      if (!(ss >> e.name >> e.count) || e.count < 0)
        throw InputError(file, line, 9, "element", "expected 'element <name> <count>'");
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty())
        throw InputError(file, line, 1, "property", "a property before any element");
      std::string type, name;
      ss >> type;
      Property p;
      if (type == "list") {
        std::string count_type, item_type;
        ss >> count_type >> item_type >> name;
        typeOf(count_type, line);
        typeOf(item_type, line);
        p.size = 0;
      } else {
        ss >> name;
        const auto [size, kind] = typeOf(type, line);
        p.size = size;
        p.kind = kind;
      }
      p.name = name;
      elements.back().props.push_back(p);
    } else if (word == "end_header") {
      ended = true;
    } else if (!word.empty() && word != "comment" && word != "obj_info") {
      throw InputError(file, line, 1, word, "unknown PLY header line");
    }
  }
  if (!ended) throw InputError(file, line, 0, "end_header", "the PLY header has no end_header");
  if (format.empty()) throw InputError(file, 2, 0, "format", "the PLY header has no format");
  size_t vertex = elements.size();
  for (size_t k = 0; k < elements.size(); ++k)
    if (elements[k].name == "vertex") {
      vertex = k;
      break;
    }
  if (vertex == elements.size())
    throw InputError(file, line, 0, "vertex", "the PLY file has no vertex element");
  const Element& v = elements[vertex];
  int ix[6] = {-1, -1, -1, -1, -1, -1};
  static const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (size_t k = 0; k < v.props.size(); ++k)
    for (int c = 0; c < 6; ++c)
      if (v.props[k].name == names[c]) {
        if (v.props[k].size == 0)
          throw InputError(file, 0, 0, names[c], "a list property where a number goes");
        ix[c] = static_cast<int>(k);
      }
  for (int c = 0; c < 3; ++c)
    if (ix[c] < 0)
      throw InputError(file, line, 0, names[c],
                       "the vertex element has no property " + std::string(names[c]));
  const bool normals = ix[3] >= 0 && ix[4] >= 0 && ix[5] >= 0;
  std::vector<MeasuredPoint> out;
  const bool ascii = format == "ascii";
  const bool swap = format == "binary_big_endian";
  size_t record = 0;
  for (const Property& p : v.props) record += static_cast<size_t>(p.size);
  for (size_t k = 0; k < vertex; ++k)
    for (const Property& p : elements[k].props)
      if (p.size == 0 || ascii)
        throw InputError(file, line, 0, elements[k].name,
                         "elements before the vertices are not read: write the vertices first");
  // Binary: skip what comes before the vertices, then check the size before allocating.
  if (!ascii) {
    for (size_t k = 0; k < vertex; ++k) {
      size_t r = 0;
      for (const Property& p : elements[k].props) r += static_cast<size_t>(p.size);
      const size_t left = text.size() - std::min(pos, text.size());
      if (r > 0 && static_cast<unsigned long long>(elements[k].count) > left / r)
        throw InputError(file, line, 0, elements[k].name,
                         "the file is shorter than its " + std::to_string(elements[k].count) + " " +
                             elements[k].name + " elements");
      pos += r * static_cast<size_t>(elements[k].count);
    }
    if (pos > text.size() || static_cast<unsigned long long>(v.count) >
                                 (text.size() - pos) / std::max<size_t>(1, record))
      throw InputError(file, line, 0, "vertex",
                       "the file is shorter than its " + std::to_string(v.count) + " vertices");
  } else if (static_cast<unsigned long long>(v.count) > text.size() - std::min(pos, text.size())) {
    throw InputError(file, line, 0, "vertex",
                     "the file is shorter than its " + std::to_string(v.count) + " vertices");
  }
  out.reserve(static_cast<size_t>(v.count));
  const bool host_little = [] {
    const uint16_t one = 1;
    unsigned char c;
    std::memcpy(&c, &one, 1);
    return c == 1;
  }();
  auto binaryValue = [&](const char* at, const Property& p) {
    unsigned char b[8];
    std::memcpy(b, at, static_cast<size_t>(p.size));
    if (swap == host_little) std::reverse(b, b + p.size);
    if (p.kind == 'f') return p.size == 4 ? loadAs<float>(b) : loadAs<double>(b);
    if (p.kind == 'i')
      return p.size == 1   ? loadAs<int8_t>(b)
             : p.size == 2 ? loadAs<int16_t>(b)
                           : loadAs<int32_t>(b);
    return p.size == 1   ? loadAs<uint8_t>(b)
           : p.size == 2 ? loadAs<uint16_t>(b)
                         : loadAs<uint32_t>(b);
  };
  for (long long i = 0; i < v.count; ++i) {
    double val[6] = {0, 0, 0, 0, 0, 0};
    int at_line = 0;
    if (ascii) {
      std::string l;
      do {
        if (pos >= text.size())
          throw InputError(file, line, 0, "vertex",
                           "the file ends after " + std::to_string(i) + " of its " +
                               std::to_string(v.count) + " vertices");
        size_t eol = text.find('\n', pos);
        if (eol == std::string::npos) eol = text.size();
        l = text.substr(pos, eol - pos);
        pos = eol + 1;
        ++line;
      } while (trim(l).empty());
      at_line = line;
      std::istringstream ss(l);
      for (size_t k = 0; k < v.props.size(); ++k) {
        std::string cell;
        if (!(ss >> cell)) throw InputError(file, line, 0, v.props[k].name, "missing value");
        for (int c = 0; c < 6; ++c)
          if (ix[c] == static_cast<int>(k)) {
            const auto x = parseNumber(cell);
            if (!x) throw InputError(file, line, 0, names[c], "'" + cell + "' is not a number");
            val[c] = *x;
          }
      }
    } else {
      at_line = static_cast<int>(std::min<long long>(i + 1, 2000000000));
      const char* rec = text.data() + pos;
      size_t off = 0;
      for (size_t k = 0; k < v.props.size(); ++k) {
        for (int c = 0; c < 6; ++c)
          if (ix[c] == static_cast<int>(k)) val[c] = binaryValue(rec + off, v.props[k]);
        off += static_cast<size_t>(v.props[k].size);
      }
      pos += record;
    }
    MeasuredPoint m;
    m.p = Eigen::Vector3d(val[0], val[1], val[2]);
    if (normals) m.n = Eigen::Vector3d(val[3], val[4], val[5]);
    for (int c = 0; c < (normals ? 6 : 3); ++c)
      if (!std::isfinite(val[c]) || std::abs(val[c]) > 1e7)
        throw InputError(file, ascii ? at_line : 0, 0, names[c],
                         (ascii ? std::string() : "vertex " + std::to_string(i + 1) + ": ") +
                             "value out of range");
    if (normals) {
      if (m.n.norm() < 1e-9)
        m.n.setZero();  // no normal: the mesh's
      else
        m.n.normalize();
    }
    m.line = at_line;
    out.push_back(m);
  }
  return out;
}

}  // namespace

std::vector<MeasuredPoint> parseMeasuredPoints(const std::string& text, const std::string& file) {
  if (text.compare(0, 4, "ply\n") == 0 || text.compare(0, 5, "ply\r\n") == 0)
    return parsePly(text, file);
  const std::vector<std::string> lines = splitLines(text);
  for (const std::string& l : lines) {
    const std::string_view t = trim(l);
    if (t.empty() || t[0] == '#' || t[0] == '/') continue;
    if (numericLine(std::string(t))) return parseAsc(lines, file);
    break;
  }
  std::vector<MeasuredPoint> out;
  std::string xs = "x_mm", ys = "y_mm", zs = "z_mm", ds = "deviation_mm";
  bool nominal_table = false;
  forEachCsvRow(
      text, file, {}, "",
      [&](const CsvRow& row) {
        auto number = [&](const std::string& name) {
          const std::string c = row.cell(name);
          if (c.empty()) throw InputError(file, row.line, row.column(name), name, "missing value");
          const auto v = parseNumber(c);
          if (!v)
            throw InputError(file, row.line, row.column(name), name, "'" + c + "' is not a number");
          if (!(std::abs(*v) <= kLimit))
            throw InputError(file, row.line, row.column(name), name,
                             "'" + c + "' is out of range (within 1e6 mm)");
          return *v;
        };
        MeasuredPoint p;
        p.line = row.line;
        p.p = Eigen::Vector3d(number(xs), number(ys), number(zs));
        const int given =
            !row.cell("nx").empty() + !row.cell("ny").empty() + !row.cell("nz").empty();
        if (given == 3) {
          p.n = Eigen::Vector3d(number("nx"), number("ny"), number("nz"));
          checkNormal(p, file, row.column("nx"));
        } else if (given != 0) {
          throw InputError(file, row.line, row.column("nx"), "nx",
                           "give all three of nx, ny, nz or none");
        }
        if (!row.cell(ds).empty()) {
          p.deviation = number(ds);
          p.has_deviation = true;
        }
        if (nominal_table) {  // the measured point: the nominal moved by the deviation along n
          if (given != 3 || !p.has_deviation)
            throw InputError(file, row.line, given != 3 ? row.column("nx") : row.column(ds),
                             given != 3 ? "nx" : ds,
                             "a deviation table (nominal_x_mm, ...) needs the normal and the "
                             "deviation on every row");
          p.p += p.deviation * p.n;
        }
        out.push_back(p);
      },
      [&](const CsvHeader& h) {
        if (!h.has("x_mm") && h.has("x")) xs = "x", ys = "y", zs = "z";
        if (!h.has("x_mm") && h.has("actual_x_mm"))
          xs = "actual_x_mm", ys = "actual_y_mm", zs = "actual_z_mm";
        if (!h.has("x_mm") && !h.has("x") && !h.has("actual_x_mm") && h.has("nominal_x_mm")) {
          xs = "nominal_x_mm", ys = "nominal_y_mm", zs = "nominal_z_mm";
          nominal_table = true;
        }
        if (!h.has("deviation_mm") && h.has("deviation")) ds = "deviation";
        for (const std::string& c : {xs, ys, zs})
          if (!h.has(c))
            throw InputError(file, h.line, 0, c,
                             "missing column (header: x_mm,y_mm,z_mm[,nx,ny,nz][,deviation_mm])");
      });
  return out;
}

std::vector<MeasuredPoint> readMeasuredPoints(const std::string& path) {
  std::vector<MeasuredPoint> p = parseMeasuredPoints(readFile(path), path);
  if (p.empty()) throw InputError(path, 0, 0, "x_mm", "no measured points");
  return p;
}

}  // namespace tolver
