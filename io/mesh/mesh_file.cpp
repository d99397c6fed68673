#include "io/mesh/mesh_file.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <tinyxml2.h>
#include <unistd.h>
#include <unzip.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string_view>
#include <vector>

#include "core/numerics/lazy_module.h"
#include "core/numerics/quantities.h"
#include "io/common/child_process.h"
#include "io/common/io_error.h"
#include "io/mesh/mesh_bytes.h"

namespace tolver {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// PLY's scalar types: their size in bytes, whether integer, whether signed (a list's count must be
// of an integer type, and holds at most what its size and sign allow). Size 0: not a PLY type.
struct PlyType {
  int size = 0;
  bool integer = false, is_signed = false;
};

PlyType plyType(std::string_view t) {
  if (t == "char" || t == "int8") return {1, true, true};
  if (t == "uchar" || t == "uint8") return {1, true, false};
  if (t == "short" || t == "int16") return {2, true, true};
  if (t == "ushort" || t == "uint16") return {2, true, false};
  if (t == "int" || t == "int32") return {4, true, true};
  if (t == "uint" || t == "uint32") return {4, true, false};
  if (t == "float" || t == "float32") return {4, false, true};
  if (t == "double" || t == "float64") return {8, false, true};
  return {};
}

// A property as its header line declares it: a scalar (count.size == 0) or a list.
struct PlyProperty {
  PlyType count, item;
};

struct PlyElement {
  std::string name;
  unsigned long long count;
  int line;
  std::vector<PlyProperty> properties;
};

std::vector<std::string_view> words(std::string_view text) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    const size_t from = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
    if (i > from) out.push_back(text.substr(from, i - from));
  }
  return out;
}

bool isCount(std::string_view t) {
  return !t.empty() && t.size() < 19 &&
         std::all_of(t.begin(), t.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
}

std::string printable(std::string_view text) {  // a binary file's bytes are not echoed
  std::string out(text.substr(0, 80));
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return out;
}

// An ASCII PLY's body as assimp reads it: one line per element instance. Each line must hold
// exactly the numbers its element's properties take, each list's count within its type.
void checkPlyAsciiBody(const std::string& path, const std::string& text, size_t at, int line,
                       const std::vector<PlyElement>& elements) {
  std::vector<std::string_view> tokens;
  for (const PlyElement& e : elements)
    for (unsigned long long i = 0; i < e.count; ++i) {
      // The instance's line: blank lines are skipped.
      std::string_view row;
      do {
        if (at >= text.size())
          throw InputError(path, line, 0, "PLY body",
                           "the file ends before " + e.name + " " + std::to_string(i + 1) +
                               " of the " + std::to_string(e.count) +
                               " its header declares (line " + std::to_string(e.line) + ")");
        size_t end = text.find('\n', at);
        if (end == std::string::npos) end = text.size();
        row = std::string_view(text).substr(at, end - at);
        if (!row.empty() && row.back() == '\r') row.remove_suffix(1);
        at = end + 1;
        ++line;
      } while (row.find_first_not_of(" \t") == std::string_view::npos);
      tokens = words(row);
      size_t k = 0;
      auto fail = [&](const std::string& why) {
        throw InputError(
            path, line - 1, 0, "PLY body",
            e.name + " " + std::to_string(i + 1) + " '" + printable(row) + "': " + why);
      };
      auto number = [&] {
        if (k >= tokens.size()) fail("fewer numbers than the header's properties take");
        const std::string_view t = tokens[k++];
        char buf[64];
        if (t.size() >= sizeof buf) fail("'" + printable(t) + "' is not a number");
        std::memcpy(buf, t.data(), t.size());
        buf[t.size()] = '\0';
        char* end = nullptr;
        std::strtod(buf, &end);
        if (end != buf + t.size()) fail("'" + printable(t) + "' is not a number");
      };
      for (const PlyProperty& p : e.properties) {
        if (p.count.size == 0) {
          number();
          continue;
        }
        if (k >= tokens.size()) fail("fewer numbers than the header's properties take");
        const std::string_view t = tokens[k++];
        const unsigned long long max =
            (1ull << (8 * p.count.size - (p.count.is_signed ? 1 : 0))) - 1;
        if (!isCount(t) || std::stoull(std::string(t)) > max)
          fail("list count '" + printable(t) + "' is not a count its type can hold");
        for (unsigned long long n = std::stoull(std::string(t)); n > 0; --n) number();
      }
      if (k != tokens.size()) fail("more numbers than the header's properties take");
    }
}

// A binary PLY's body: every list's count read in the file's byte order, and every element
// within the file.
void checkPlyBinaryBody(const std::string& path, const std::string& bytes, size_t at,
                        bool big_endian, const std::vector<PlyElement>& elements) {
  for (const PlyElement& e : elements)
    for (unsigned long long i = 0; i < e.count; ++i)
      for (const PlyProperty& p : e.properties) {
        auto ends = [&] {
          throw InputError(path, 0, 0, "PLY body",
                           "the file ends in " + e.name + " " + std::to_string(i + 1) + " of the " +
                               std::to_string(e.count) + " its header declares (line " +
                               std::to_string(e.line) + ")");
        };
        if (p.count.size == 0) {
          if (bytes.size() - at < static_cast<size_t>(p.item.size)) ends();
          at += p.item.size;
          continue;
        }
        if (bytes.size() - at < static_cast<size_t>(p.count.size)) ends();
        unsigned long long n = 0;
        for (int b = 0; b < p.count.size; ++b) {
          const auto byte =
              static_cast<unsigned char>(bytes[at + (big_endian ? b : p.count.size - 1 - b)]);
          n = (n << 8) | byte;
        }
        at += p.count.size;
        if (p.count.is_signed && (n >> (8 * p.count.size - 1)) != 0)
          throw InputError(path, 0, 0, "PLY body",
                           e.name + " " + std::to_string(i + 1) + " has a negative list count");
        if (n > (bytes.size() - at) / p.item.size) ends();
        at += n * p.item.size;
      }
}

// A PLY is checked whole before assimp reads it: Debian's assimp 5.2 trusts the counts it reads
// and allocates from them, and reads past a header it does not understand. The mesh fuzz harness
// found, one after another: a header without end_header (minutes of allocating), element counts
// beyond the file (26 GB), faces before any vertex (50 s, 17 GB), a list count of a run of 4s
// (7.5 GB), and zero bytes inside a property line (3.8 GB). So every header line must be one of
// PLY's in its exact form (format, element <name> <count>, property <type> <name>, property
// list <type> <type> <name>, comment, obj_info), in text, with end_header in the first 64 kB;
// and the body must hold exactly what the header declares: in ASCII one line per element, in
// binary every list's count within the file.
void checkPly(const std::string& path, const std::string& bytes) {
  const std::string_view head = std::string_view(bytes).substr(0, 65536);
  bool seen_vertex = false, ascii = false, big_endian = false, seen_format = false;
  std::vector<PlyElement> elements;
  size_t start = 0;
  for (int line = 1; start < head.size(); ++line) {
    size_t end = head.find('\n', start);
    if (end == std::string::npos) break;
    std::string_view text = head.substr(start, end - start);
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    const std::vector<std::string_view> w = words(text);
    const std::string_view word = w.empty() ? std::string_view() : w[0];
    auto refuse = [&](const char* field, const std::string& why) {
      throw InputError(path, line, 0, field, "'" + printable(text) + "' " + why);
    };
    const bool comment = word == "comment" || word == "obj_info";
    for (char c : text)
      if ((static_cast<unsigned char>(c) < 0x20 && c != '\t') ||
          (!comment && static_cast<unsigned char>(c) >= 0x7f))
        refuse("PLY header", "is not a PLY header line (it holds bytes that are not text)");
    if (line == 1) {
      if (w.size() != 1 || word != "ply")
        refuse("PLY header", "is not a PLY header line (a PLY starts with 'ply')");
    } else if (word == "end_header" && w.size() == 1) {
      if (!seen_format)
        throw InputError(path, line, 0, "PLY header", "no format line before end_header");
      if (!seen_vertex)
        throw InputError(path, line, 0, "PLY header", "no 'element vertex' before end_header");
      if (ascii)
        checkPlyAsciiBody(path, bytes, end + 1, line + 1, elements);
      else
        checkPlyBinaryBody(path, bytes, end + 1, big_endian, elements);
      return;
    } else if (word == "format") {
      if (w.size() != 3 || w[2] != "1.0" ||
          (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian"))
        refuse("PLY format", "is not 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (seen_format || !elements.empty())
        refuse("PLY format", "comes after the format or an element");
      seen_format = true;
      ascii = w[1] == "ascii";
      big_endian = w[1] == "binary_big_endian";
    } else if (word == "element") {
      if (w.size() != 3 || !isCount(w[2]))
        refuse("PLY element", "is not 'element <name> <count>' with a count below 1e18");
      const std::string name(w[1]);
      const unsigned long long count = std::stoull(std::string(w[2]));
      // assimp reads faces against the vertices read before them; without them it spent 50 s
      // and 17 GB on a fuzzed file before saying so (an 'element vbspertex' in its place).
      if (name == "vertex") seen_vertex = true;
      if (name == "face" && !seen_vertex)
        refuse("PLY element", "comes before any 'element vertex' (the vertices must come first)");
      // At least a byte per element in any of PLY's formats.
      if (count > bytes.size())
        refuse("PLY element", "declares more " + name + " elements than the file's " +
                                  std::to_string(bytes.size()) + " bytes can hold");
      elements.push_back({name, count, line, {}});
    } else if (word == "property") {
      if (elements.empty()) refuse("PLY property", "comes before any element");
      PlyProperty p;
      if (w.size() == 3) {
        p.item = plyType(w[1]);
      } else if (w.size() == 5 && w[1] == "list") {
        p.count = plyType(w[2]);
        p.item = plyType(w[3]);
        if (!p.count.integer) p.item.size = 0;
      }
      if (p.item.size == 0)
        refuse("PLY property",
               "is not 'property <type> <name>' or 'property list <integer type> <type> <name>'");
      elements.back().properties.push_back(p);
    } else if (!comment) {
      refuse("PLY header", "is not a PLY header line (the header must end with end_header)");
    }
    start = end + 1;
  }
  throw InputError(path, 0, 0, "PLY header", "no end_header line in the first 64 kB");
}

Eigen::Matrix4d toEigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return e;
}

void collect(const aiScene* scene, const aiNode* node, const Eigen::Matrix4d& parent,
             TriangleMesh* out, std::vector<char>* seen_mesh) {
  const Eigen::Matrix4d T = parent * toEigen(node->mTransformation);
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const unsigned mi = node->mMeshes[k];
    const aiMesh* m = scene->mMeshes[mi];
    std::string name = m->mName.length > 0 ? m->mName.C_Str() : node->mName.C_Str();
    if (name.empty() || name == "defaultobject") name = "part";
    if ((*seen_mesh)[mi]) name.append(1, '#').append(std::to_string(out->group_names.size()));
    (*seen_mesh)[mi] = 1;
    int group;
    auto it = std::find(out->group_names.begin(), out->group_names.end(), name);
    if (it == out->group_names.end()) {
      group = static_cast<int>(out->group_names.size());
      out->group_names.push_back(name);
    } else {
      group = static_cast<int>(it - out->group_names.begin());
    }
    const int base = static_cast<int>(out->vertices.size());
    for (unsigned v = 0; v < m->mNumVertices; ++v) {
      const Eigen::Vector4d p(m->mVertices[v].x, m->mVertices[v].y, m->mVertices[v].z, 1.0);
      out->vertices.push_back((T * p).head<3>());
    }
    for (unsigned f = 0; f < m->mNumFaces; ++f) {
      const aiFace& face = m->mFaces[f];
      if (face.mNumIndices != 3) continue;
      out->faces.emplace_back(base + static_cast<int>(face.mIndices[0]),
                              base + static_cast<int>(face.mIndices[1]),
                              base + static_cast<int>(face.mIndices[2]));
      out->face_group.push_back(group);
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c)
    collect(scene, node->mChildren[c], T, out, seen_mesh);
}

// An OFF file's vertex and face counts must fit in the file (a byte per element at least):
// Debian's assimp 5.2 allocates the faces the header declares before reading any (the mesh
// harness: 'OFF' then '8 1888...880', and 'OFF8' then '2222222223222222220', each made it ask
// for more than 2 GB). The header is read as assimp reads it: spaces, line ends and '#' lines
// skipped, the prefixes [ST][C][N][4][n] and the keyword OFF (optional, and the counts may follow
// it without a space), a dimension after an 'n', then the vertex and face counts.
void checkOffHeader(const std::string& path) {
  std::error_code size_error;
  const auto file_size = std::filesystem::file_size(path, size_error);
  if (size_error) return;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, 0, 0, "mesh", "cannot open the file");
  std::string head(4096, '\0');
  head.resize(std::fread(head.data(), 1, head.size(), f));
  std::fclose(f);
  size_t i = 0;
  int line = 1;
  auto next = [&] {
    for (;;) {
      while (i < head.size() &&
             (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n'))
        if (head[i++] == '\n') ++line;
      if (i < head.size() && head[i] == '#') {
        while (i < head.size() && head[i] != '\n') ++i;
        continue;
      }
      return;
    }
  };
  auto at = [&](const char* word) { return head.compare(i, std::strlen(word), word) == 0; };
  next();
  if (at("ST")) i += 2;
  if (at("C")) ++i;
  if (at("N")) ++i;
  if (at("4")) ++i;
  const bool dimension = at("n");
  if (dimension) ++i;
  if (at("OFF")) i += 3;
  next();
  for (int k = 0; k < (dimension ? 3 : 2); ++k) {
    size_t j = i;
    while (j < head.size() && std::isdigit(static_cast<unsigned char>(head[j]))) ++j;
    if (j == i) return;  // no number: assimp says what is wrong
    const std::string number = head.substr(i, j - i);
    if (number.size() >= 19 || std::stoull(number) > file_size)
      throw InputError(path, line, 0, "OFF header",
                       "count '" + number + "' is more than the file's " +
                           std::to_string(file_size) + " bytes can hold");
    i = j;
    next();
  }
}

// A 3MF archive is checked before assimp reads it: Debian's assimp 5.2 aborts the process (an
// ai_assert in D3MFOpcPackage) when the model its package relationship names cannot be opened
// (the scene fuzz harness, in its first seconds: one corrupt byte in the deflated model). So every
// entry must inflate with its CRC right, _rels/.rels must name the 3D model as assimp looks for
// it, and that model must be in the archive. A file of another format that opens as a zip is
// checked the same way (required false): assimp, when a file does not parse as its extension
// says, tries every reader by content, and its 3MF reader takes any zip (the scene harness: a
// .gltf holding a zip reached the same abort).
void check3mf(const std::string& path, bool required) {
  unzFile zip = unzOpen64(path.c_str());
  if (!zip && !required) return;
  // Said as what the file was read as: a 3MF, or a zip inside a file of another format.
  const std::string field = required ? "3MF" : "zip archive read as 3MF";
  if (!zip) throw InputError(path, 0, 0, field, "not a zip archive (a 3MF file is one)");
  struct Closer {
    unzFile z;
    ~Closer() { unzClose(z); }
  } closer{zip};
  std::vector<std::string> names;
  std::string rels;
  std::vector<char> buffer(1 << 16);
  int rc = unzGoToFirstFile(zip);
  for (; rc == UNZ_OK; rc = unzGoToNextFile(zip)) {
    char name[1024] = {};
    unz_file_info64 info;
    if (unzGetCurrentFileInfo64(zip, &info, name, sizeof name - 1, nullptr, 0, nullptr, 0) !=
        UNZ_OK)
      throw InputError(path, 0, 0, field, "the archive's directory is damaged");
    names.emplace_back(name);
    const bool is_rels = names.back() == "_rels/.rels";
    if (unzOpenCurrentFile(zip) != UNZ_OK)
      throw InputError(path, 0, 0, field, "entry '" + printable(name) + "' cannot be opened");
    int n;
    unsigned long long size = 0;
    while ((n = unzReadCurrentFile(zip, buffer.data(), static_cast<unsigned>(buffer.size()))) > 0) {
      size += static_cast<unsigned>(n);
      if (is_rels && rels.size() < (1u << 20)) rels.append(buffer.data(), n);
    }
    // (minizip checks the CRC only when the entry inflated to its declared size: a stream that
    // ends early is caught by its size; the harness found one.)
    const int closed = unzCloseCurrentFile(zip);
    if (n < 0 || closed != UNZ_OK || size != info.uncompressed_size)
      throw InputError(path, 0, 0, field,
                       "entry '" + printable(name) + "' is damaged (" +
                           (closed == UNZ_CRCERROR ? "its checksum is wrong"
                            : n < 0                ? "it does not inflate"
                                    : "it inflates to " + std::to_string(size) + " of its " +
                                          std::to_string(info.uncompressed_size) + " bytes") +
                           ")");
  }
  if (rc != UNZ_END_OF_LIST_OF_FILE)
    throw InputError(path, 0, 0, field, "the archive's directory is damaged");
  if (std::find(names.begin(), names.end(), "_rels/.rels") == names.end())
    throw InputError(path, 0, 0, field, "no _rels/.rels in the archive (it names the 3D model)");
  tinyxml2::XMLDocument doc;
  if (doc.Parse(rels.data(), rels.size()) != tinyxml2::XML_SUCCESS || !doc.RootElement())
    throw InputError(path, 0, 0, field, "_rels/.rels is not XML");
  std::string target;
  for (const tinyxml2::XMLElement* r = doc.RootElement()->FirstChildElement("Relationship"); r;
       r = r->NextSiblingElement("Relationship")) {
    const char* type = r->Attribute("Type");
    const char* to = r->Attribute("Target");
    if (type && to &&
        std::string(type) == "http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel") {
      target = to;
      break;
    }
  }
  // As assimp reads it: up to two leading slashes dropped.
  for (int k = 0; k < 2 && !target.empty() && target[0] == '/'; ++k) target.erase(0, 1);
  if (target.empty())
    throw InputError(path, 0, 0, field,
                     "_rels/.rels names no 3D model (a Relationship of type .../3dmodel)");
  if (std::find(names.begin(), names.end(), target) == names.end())
    throw InputError(
        path, 0, 0, field,
        "the 3D model '" + printable(target) + "' that _rels/.rels names is not in the archive");
}

// A binary glTF's header and chunk lengths must fit in the file: Debian's assimp 5.2 allocates
// the JSON chunk's declared length before reading it (the scene harness: a length of 0xf8000000
// in a 3 kB file asked for 4.2 GB). Layout (glTF 2.0, little-endian): 'glTF', version, total
// length, then chunks of (length, type, data): JSON first, BIN optionally after it.
// RFC 4648 base64 (the data URIs of glTF buffers); characters outside the alphabet end it.
std::string base64Decode(std::string_view text) {
  std::string out;
  unsigned bits = 0;
  int have = 0;
  for (char c : text) {
    int v;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else
      break;
    bits = (bits << 6) | static_cast<unsigned>(v);
    have += 6;
    if (have >= 8) {
      have -= 8;
      out.push_back(static_cast<char>((bits >> have) & 0xff));
    }
  }
  return out;
}

// The meshes of a glTF 2 document checked as the specification requires before assimp reads them
// (glTF 2.0, 3.7.2.1 and 5.1): every primitive has a POSITION accessor of VEC3 floats; every
// accessor lies inside its buffer view and every view inside its buffer; and every index is
// below the primitive's vertex count. Debian's assimp 5.2 reads past the vertices on a line loop
// whose indices pass them (a segmentation fault) and allocates 2^32 faces for a strip without
// positions (the scene fuzz harness; tests/fuzz/scene_corpus): both are refused here, naming the
// mesh and primitive. bin: the binary chunk of a .glb (the buffer without a uri); a buffer given by
// a base64 data URI is decoded, an external one read beside the file.
void checkGltfMeshes(const std::string& path, const std::string& json_text,
                     const std::string& bin) {
  const nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
  auto refuse = [&](const std::string& what) { throw InputError(path, 0, 0, "glTF", what); };
  if (doc.is_discarded() || !doc.is_object()) refuse("the JSON does not parse");
  auto array = [&](const char* name) {
    const auto it = doc.find(name);
    return it != doc.end() && it->is_array() ? *it : nlohmann::json::array();
  };
  const nlohmann::json accessors = array("accessors"), views = array("bufferViews"),
                       buffers = array("buffers"), meshes = array("meshes");
  auto count = [](const nlohmann::json& o, const char* key) -> long long {
    const auto it = o.find(key);
    return it != o.end() && it->is_number_unsigned() ? it->get<long long>() : -1;
  };
  // The bytes of buffer b (empty when not resolved: assimp then says what is missing).
  std::map<long long, std::string> buffer_bytes;
  auto bufferBytes = [&](long long b) -> const std::string& {
    auto it = buffer_bytes.find(b);
    if (it != buffer_bytes.end()) return it->second;
    std::string bytes;
    const nlohmann::json& buf = buffers[static_cast<size_t>(b)];
    const auto uri = buf.find("uri");
    if (uri == buf.end()) {
      bytes = bin;
    } else if (uri->is_string()) {
      const std::string u = uri->get<std::string>();
      const size_t comma = u.find(";base64,");
      if (u.rfind("data:", 0) == 0 && comma != std::string::npos) {
        bytes = base64Decode(std::string_view(u).substr(comma + 8));
      } else if (u.find("..") == std::string::npos && u.find(':') == std::string::npos) {
        const std::filesystem::path beside = std::filesystem::path(path).parent_path() / u;
        std::error_code e;
        if (std::filesystem::is_regular_file(beside, e)) bytes = readFile(beside.string());
      }
    }
    return buffer_bytes.emplace(b, std::move(bytes)).first->second;
  };
  // Accessor a: its element count, component size and components, checked inside its view.
  struct Span {
    long long count = 0, type = 0, component = 0, components = 0, view = -1, offset = 0, stride = 0;
  };
  auto accessor = [&](const nlohmann::json& ref, const std::string& where) {
    if (!ref.is_number_unsigned() || ref.get<unsigned long long>() >= accessors.size())
      refuse(where + " names no accessor");
    const nlohmann::json& a = accessors[ref.get<size_t>()];
    Span s;
    s.count = count(a, "count");
    const long long type = s.type = count(a, "componentType");
    s.component = type == 5120 || type == 5121   ? 1
                  : type == 5122 || type == 5123 ? 2
                  : type == 5125 || type == 5126 ? 4
                                                 : 0;
    const auto t = a.find("type");
    const std::string kind = t != a.end() && t->is_string() ? t->get<std::string>() : "";
    s.components = kind == "SCALAR" ? 1
                   : kind == "VEC2" ? 2
                   : kind == "VEC3" ? 3
                   : kind == "VEC4" ? 4
                                    : 0;
    if (s.count < 1 || s.component == 0 || s.components == 0)
      refuse(where + ": an accessor without a count, component type or type");
    s.view = count(a, "bufferView");
    if (s.view < 0) return s;  // no view: zeros (glTF 2.0, 3.6.2.3)
    if (s.view >= static_cast<long long>(views.size())) refuse(where + ": no such buffer view");
    const nlohmann::json& v = views[static_cast<size_t>(s.view)];
    const long long buffer = count(v, "buffer"), length = count(v, "byteLength");
    const long long view_offset = std::max(0ll, count(v, "byteOffset"));
    const long long offset = std::max(0ll, count(a, "byteOffset"));
    s.stride = std::max(count(v, "byteStride"), s.component * s.components);
    if (buffer < 0 || buffer >= static_cast<long long>(buffers.size()) || length < 0 ||
        count(buffers[static_cast<size_t>(buffer)], "byteLength") < view_offset + length)
      refuse(where + ": its buffer view lies outside its buffer");
    if (s.count > (1ll << 40) / s.stride ||
        offset + (s.count - 1) * s.stride + s.component * s.components > length)
      refuse(where + ": its accessor runs past its buffer view");
    s.offset = view_offset + offset;
    s.view = buffer;  // from here on: the buffer
    return s;
  };
  for (size_t m = 0; m < meshes.size(); ++m) {
    const auto prims = meshes[m].find("primitives");
    if (prims == meshes[m].end() || !prims->is_array()) continue;
    for (size_t k = 0; k < prims->size(); ++k) {
      const nlohmann::json& prim = (*prims)[k];
      const std::string where = "mesh " + std::to_string(m) + " primitive " + std::to_string(k);
      const auto attributes = prim.find("attributes");
      if (attributes == prim.end() || !attributes->is_object() || !attributes->contains("POSITION"))
        refuse(where + " has no POSITION attribute (glTF 2.0 requires one)");
      const Span position = accessor((*attributes)["POSITION"], where + " POSITION");
      if (position.components != 3 || position.component != 4)
        refuse(where + ": POSITION is not VEC3 of floats");
      const auto indices = prim.find("indices");
      if (indices == prim.end()) continue;
      const Span index = accessor(*indices, where + " indices");
      if (index.components != 1 || (index.type != 5121 && index.type != 5123 && index.type != 5125))
        refuse(where + ": its indices are not unsigned integer scalars");
      if (index.view < 0) continue;  // all zero
      const std::string& bytes = bufferBytes(index.view);
      if (bytes.empty()) continue;  // unresolved: assimp says so
      if (static_cast<long long>(bytes.size()) <
          index.offset + (index.count - 1) * index.stride + index.component)
        refuse(where + ": its indices lie past the end of the buffer's data");
      for (long long i = 0; i < index.count; ++i) {
        const unsigned char* at =
            reinterpret_cast<const unsigned char*>(bytes.data()) + index.offset + i * index.stride;
        unsigned long long value = 0;
        for (long long b = index.component - 1; b >= 0; --b) value = (value << 8) | at[b];
        if (value >= static_cast<unsigned long long>(position.count))
          refuse(where + ": index " + std::to_string(i) + " is " + std::to_string(value) +
                 ", past its " + std::to_string(position.count) + " vertices");
      }
    }
  }
}

void checkGlb(const std::string& path) {
  std::error_code size_error;
  const unsigned long long size = std::filesystem::file_size(path, size_error);
  if (size_error) return;
  std::ifstream in(path, std::ios::binary);
  auto bytesAt = [&](unsigned long long at, size_t n) {
    std::string b(n, '\0');
    in.clear();
    in.seekg(static_cast<std::streamoff>(at));
    in.read(b.data(), static_cast<std::streamsize>(n));
    b.resize(static_cast<size_t>(in.gcount()));
    return b;
  };
  auto u32 = [](const std::string& b, size_t at) {
    unsigned long long v = 0;
    for (int k = 3; k >= 0; --k) v = (v << 8) | static_cast<unsigned char>(b[at + k]);
    return v;
  };
  const std::string head = bytesAt(0, 20);
  if (head.size() < 20 || head.compare(0, 4, "glTF") != 0)
    throw InputError(path, 0, 0, "glTF",
                     "not a binary glTF (it starts with 'glTF' and a 20-byte header)");
  if (u32(head, 4) != 2)
    throw InputError(path, 0, 0, "glTF",
                     "version " + std::to_string(u32(head, 4)) + " (tolver reads glTF 2)");
  if (u32(head, 8) > size)
    throw InputError(path, 0, 0, "glTF",
                     "the header declares " + std::to_string(u32(head, 8)) +
                         " bytes; the file has " + std::to_string(size));
  const unsigned long long json = u32(head, 12);
  if (head.compare(16, 4, "JSON") != 0 || 20 + json > size)
    throw InputError(path, 0, 0, "glTF",
                     "the first chunk is not JSON within the file (" + std::to_string(json) +
                         " bytes declared, " + std::to_string(size) + " in the file)");
  const unsigned long long bin_at = 20 + ((json + 3) & ~3ull);
  const std::string bin = bin_at + 8 <= size ? bytesAt(bin_at, 8) : std::string();
  if (bin.size() == 8 && bin_at + 8 + u32(bin, 0) > size)
    throw InputError(path, 0, 0, "glTF",
                     "the binary chunk declares " + std::to_string(u32(bin, 0)) +
                         " bytes beyond the file's " + std::to_string(size));
  checkGltfMeshes(
      path, bytesAt(20, static_cast<size_t>(json)),
      bin.size() == 8 ? bytesAt(bin_at + 8, static_cast<size_t>(u32(bin, 0))) : std::string());
}

// The file read by assimp into one mesh (its nodes' transforms applied, faces triangulated).
// ply_bytes: the PLY's bytes as checkPly checked them, handed to assimp from memory (the file is
// read once, and assimp reads what was checked).
TriangleMesh importWithAssimp(const std::string& path, const std::string& format,
                              const std::string* ply_bytes = nullptr) {
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE,
                              aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read and validated first, triangulated after: Debian's assimp 5.2 aborts the process (an
  // ai_assert in its TriangulateProcess) on a face without vertices, which a malformed PLY makes
  // (found by the mesh fuzz harness), so such faces are refused before triangulating.
  // An OBJ is handed over from memory with a zero byte after it: Debian's assimp 5.2 parses
  // numbers with strtol on its own copy of the file, which has no terminating zero, so a file
  // ending in digits would be read past its end (the mesh fuzz harness,
  // tests/fuzz/mesh_corpus/obj_strtol_unterminated).
  const aiScene* scene = nullptr;
  if (format == "obj") {
    std::string text = readFile(path);
    text.push_back('\n');
    text.push_back('\0');
    scene = importer.ReadFileFromMemory(text.data(), text.size(), aiProcess_ValidateDataStructure,
                                        "obj");
  } else if (ply_bytes) {
    scene = importer.ReadFileFromMemory(ply_bytes->data(), ply_bytes->size(),
                                        aiProcess_ValidateDataStructure, "ply");
  } else {
    scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  }
  auto unreadable = [&] {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "not a readable mesh";
    // assimp turns a failed allocation into its error string; said as what it means here.
    if (why.find("bad_alloc") != std::string::npos)
      why =
          "assimp ran out of memory reading it (a count in a damaged file beyond what the file "
          "holds?)";
    throw InputError(path, 0, 0, "mesh", why);
  };
  if (!scene || !scene->mRootNode) unreadable();
  for (unsigned m = 0; m < scene->mNumMeshes; ++m)
    for (unsigned f = 0; f < scene->mMeshes[m]->mNumFaces; ++f)
      if (scene->mMeshes[m]->mFaces[f].mNumIndices == 0)
        throw InputError(path, 0, 0, "mesh",
                         "face " + std::to_string(f + 1) + " of mesh " + std::to_string(m + 1) +
                             " has no vertex (a malformed face list)");
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_SortByPType);
  if (!scene || !scene->mRootNode) unreadable();
  TriangleMesh raw;
  std::vector<char> seen(scene->mNumMeshes, 0);
  collect(scene, scene->mRootNode, Eigen::Matrix4d::Identity(), &raw, &seen);
  return raw;
}

// The scene formats (glTF, 3MF) are read by assimp in a child process (io/common/
// child_process.h): Debian's assimp 5.2 crashed on damaged glTF files (the scene fuzz harness: a
// line loop whose indices pass its vertices, a segmentation fault; a strip without positions,
// 2^32 faces allocated), which checkGltfMeshes now refuses first; the child stays for what no
// check foresees. Under the fuzz harness (TOLVER_FUZZING) the read stays in the process, so that
// what assimp does is seen.
TriangleMesh importInChildProcess(const std::string& path, const std::string& format) {
#ifdef TOLVER_FUZZING
  constexpr bool in_process = true;
#else
  constexpr bool in_process = false;
#endif
  const std::string bytes = runInChildProcess(
      path, "assimp",
      [&] {
        // Fault injection for the test of this path (no known file crashes assimp past the
        // checks above any more): the child stops as assimp did on the scene harness's findings.
        if (!in_process && std::getenv("TOLVER_TEST_CRASH_SCENE_READER")) std::raise(SIGSEGV);
        ByteWriter w;
        putMesh(w, importWithAssimp(path, format));
        return std::move(w.bytes());
      },
      in_process);
  TriangleMesh m;
  ByteReader r(bytes);
  if (!takeMesh(r, &m))
    throw InputError(path, 0, 0, "mesh", "assimp sent a damaged mesh reading it");
  return m;
}

}  // namespace

ImportedPart readPartMesh(const std::string& path, const PartImportOptions& options) {
  ImportedPart part;
  part.format = lowerExtension(path);
  static const char* kFormats[] = {"stl", "obj", "ply", "off", "3mf", "gltf", "glb", "step", "stp"};
  if (std::find_if(std::begin(kFormats), std::end(kFormats),
                   [&](const char* f) { return part.format == f; }) == std::end(kFormats))
    throw InputError(path, 0, 0, "mesh",
                     "unsupported part format '." + part.format +
                         "' (use .step, .stp, .stl, .obj, .ply, .off, .3mf, .gltf or .glb)");
  if (!std::filesystem::is_regular_file(path))
    throw InputError(path, 0, 0, "mesh", "cannot open the file");

  const bool step = part.format == "step" || part.format == "stp";
  if (step && !options.units.empty())
    throw InputError(path, 0, 0, "units",
                     "a STEP file carries its own length unit: leave out the mesh units");
  part.units = step ? "mm"
               : options.units.empty()
                   ? ((part.format == "gltf" || part.format == "glb") ? "m" : "mm")
                   : options.units;
  double scale;
  if (part.units == "mm")
    scale = 1.0;
  else if (part.units == "inch" || part.units == "in")
    scale = 25.4;
  else if (part.units == "m")
    scale = 1000.0;
  else
    throw InputError(path, 0, 0, "units",
                     "unknown length unit '" + part.units + "' (use mm, inch or m)");

  std::string ply_bytes;
  if (part.format == "ply") {
    ply_bytes = readFile(path);
    checkPly(path, ply_bytes);
  }
  if (part.format == "off") checkOffHeader(path);
  check3mf(path, part.format == "3mf");
  if (part.format == "glb") checkGlb(path);
  if (part.format == "gltf") checkGltfMeshes(path, readFile(path), "");
  TriangleMesh raw;
  if (step) {
    StepReadOptions so;
    so.chordal_mm = options.chordal_mm;
    so.part_name = options.part_name;
#ifdef TOLVER_FUZZING
    so.in_process = true;
#endif
    part.cad = std::make_shared<StepPart>(readStepPart(path, so));
    raw = std::move(part.cad->mesh);
    part.cad->mesh = TriangleMesh();
  } else {
    raw = (part.format == "gltf" || part.format == "glb" || part.format == "3mf")
              ? importInChildProcess(path, part.format)
              : importWithAssimp(path, part.format, part.format == "ply" ? &ply_bytes : nullptr);
  }
  if (raw.faces.empty()) throw InputError(path, 0, 0, "mesh", "the file holds no triangles");
  for (auto& v : raw.vertices) v = options.w_T_file * (scale * v);
  // A vertex far beyond any part (a corrupt or mis-scaled file) would make the sampling and
  // the sweeps run for hours: parts lie within a position's range of the part frame.
  const double reach = rangeOf(Quantity::Position).hi;
  for (size_t i = 0; i < raw.vertices.size(); ++i)
    if (!raw.vertices[i].allFinite() || raw.vertices[i].cwiseAbs().maxCoeff() > reach) {
      char buf[160];
      std::snprintf(buf, sizeof buf,
                    "vertex %zu at (%.4g, %.4g, %.4g) mm lies beyond 1e5 mm of the part frame "
                    "(a corrupt file, or the wrong --mesh-units?)",
                    i, raw.vertices[i].x(), raw.vertices[i].y(), raw.vertices[i].z());
      throw InputError(path, 0, 0, "mesh", buf);
    }
  try {
    part.mesh = repairMesh(raw, options.repair, &part.repair);
  } catch (const MeshDefect& d) {
    throw InputError(path, 0, 0, "mesh", d.what());
  }
  return part;
}

void writePlyWithScalar(const std::string& path, const std::vector<Eigen::Vector3d>& points,
                        const std::vector<Eigen::Vector3i>& faces,
                        const std::vector<double>& scalar, const std::string& scalar_name) {
  // Written in pieces (a file flushed every megabyte), to a temporary renamed when complete.
  OutputSet file;
  file.addStreamed(path, [&](TextOut& out) {
    out += "ply\nformat binary_little_endian 1.0\ncomment tolver swept surface, mm, part frame\n";
    out += "element vertex " + std::to_string(points.size()) + "\n";
    out += "property float x\nproperty float y\nproperty float z\n";
    out += "property float " + scalar_name + "\n";
    out += "element face " + std::to_string(faces.size()) + "\n";
    out += "property list uchar int vertex_indices\nend_header\n";
    auto put = [&](const void* p, size_t n) {
      out += std::string_view(static_cast<const char*>(p), n);
    };
    for (size_t i = 0; i < points.size(); ++i) {
      const float v[4] = {static_cast<float>(points[i].x()), static_cast<float>(points[i].y()),
                          static_cast<float>(points[i].z()), static_cast<float>(scalar[i])};
      put(v, sizeof v);
    }
    for (const auto& f : faces) {
      char face[13];
      face[0] = 3;
      const int32_t idx[3] = {f[0], f[1], f[2]};
      std::memcpy(face + 1, idx, sizeof idx);
      put(face, sizeof face);
    }
  });
  file.commit();
}

// Written by VTK's XML writer in the tolver_vtk module (io/report/vtk_render.cpp).
void writeVtpWithScalars(
    const std::string& path, const std::vector<Eigen::Vector3d>& points,
    const std::vector<Eigen::Vector3i>& faces,
    const std::vector<std::pair<std::string, const std::vector<double>*>>& scalars) {
  moduleFunction<decltype(writeVtpWithScalars)>("tolver_vtk", "writeVtpWithScalars")(
      path, points, faces, scalars);
}

}  // namespace tolver
