#include "io/mesh/mesh_file.h"

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <vtkCellArray.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>
#include <string_view>
#include <fstream>

#include "io/common/io_error.h"

namespace tolver {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  if (!ext.empty() && ext[0] == '.') ext.erase(0, 1);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// A PLY element as its header declares it: its count, and per property -1 (a scalar) or the
// largest count its list's count type can hold.
struct PlyElement {
  unsigned long long count;
  std::vector<long long> properties;
};

long long plyCountMax(const std::string& type) {
  if (type == "char" || type == "int8") return 127;
  if (type == "uchar" || type == "uint8") return 255;
  if (type == "short" || type == "int16") return 32767;
  if (type == "ushort" || type == "uint16") return 65535;
  return 2147483647;  // int, uint and the rest: bounded by the file's size below
}

// An ASCII PLY's list counts, before assimp reads them: each must be digits, within its type and
// within what the rest of the file can hold (the mesh harness: a face count of a run of 4s made
// assimp allocate 477 million indices, 15 s and 7.5 GB, before it refused the face).
void checkPlyAsciiLists(const std::string& path, const std::vector<PlyElement>& elements,
                        int first_line, size_t body_offset) {
  std::ifstream in(path, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  size_t at = std::min(body_offset, text.size());
  int line = first_line;
  auto token = [&]() {
    while (at < text.size() && std::isspace(static_cast<unsigned char>(text[at]))) {
      if (text[at] == '\n') ++line;
      ++at;
    }
    const size_t from = at;
    while (at < text.size() && !std::isspace(static_cast<unsigned char>(text[at]))) ++at;
    return std::string_view(text).substr(from, at - from);
  };
  for (const PlyElement& e : elements)
    for (unsigned long long i = 0; i < e.count && at < text.size(); ++i)
      for (long long max : e.properties) {
        const std::string_view t = token();
        if (max < 0) continue;
        const bool digits = !t.empty() && t.size() < 19 &&
                            std::all_of(t.begin(), t.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
        const long long n = digits ? std::stoll(std::string(t)) : -1;
        if (!digits || n > max || static_cast<size_t>(n) > (text.size() - at) / 2 + 1)
          throw InputError(path, line, 0, "PLY list",
                           "list count '" + std::string(t) + "' is not a count the file can hold");
        for (long long k = 0; k < n; ++k) token();
      }
}

// A PLY header is checked before assimp reads the file: Debian's assimp 5.2 loops for minutes,
// allocating, on a header without its end_header line (found by the mesh fuzz harness: 'end_he'
// cut short). Every header line must be one of PLY's keywords, and end_header must come within
// the first 64 kB. An element's count must fit in the file, at least a byte per element in any
// of PLY's formats: assimp allocates the count before reading (the harness again: 'element face
// 7777...' asked for 26 GB).
void checkPlyHeader(const std::string& path) {
  std::error_code size_error;
  const auto file_size = std::filesystem::file_size(path, size_error);
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path, 0, 0, "mesh", "cannot open the file");
  std::string head(65536, '\0');
  head.resize(std::fread(head.data(), 1, head.size(), f));
  std::fclose(f);
  static const char* kKeywords[] = {"ply", "format", "comment", "obj_info", "element", "property"};
  bool seen_vertex = false, ascii = false;
  std::vector<PlyElement> elements;
  size_t start = 0;
  for (int line = 1; start < head.size(); ++line) {
    size_t end = head.find('\n', start);
    if (end == std::string::npos) break;
    std::string text = head.substr(start, end - start);
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const std::string word = text.substr(0, text.find_first_of(" \t"));
    if (word == "end_header") {
      if (!seen_vertex)
        throw InputError(path, line, 0, "PLY header", "no 'element vertex' before end_header");
      if (ascii) checkPlyAsciiLists(path, elements, line + 1, end + 1);
      return;
    }
    if (word == "format") ascii = text.rfind("format ascii", 0) == 0;
    if (word == "property" && !elements.empty()) {
      char kind[32] = {}, count_type[32] = {};
      elements.back().properties.push_back(-1);
      if (std::sscanf(text.c_str(), "property %31s %31s", kind, count_type) == 2 &&
          std::string(kind) == "list")
        elements.back().properties.back() = plyCountMax(count_type);
    }
    for (char& c : text)  // a binary file's bytes are not echoed
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
    if (line == 1 ? word != "ply"
                  : std::none_of(std::begin(kKeywords), std::end(kKeywords),
                                 [&](const char* k) { return word == k; }))
      throw InputError(path, line, 0, "PLY header",
                       "'" + text + "' is not a PLY header line (the header must end with end_header)");
    if (word == "element") {
      char name[64] = {}, count[32] = {}, rest[2] = {};
      const int n = std::sscanf(text.c_str(), "element %63s %31s %1s", name, count, rest);
      const std::string c = n >= 2 ? count : "";
      const bool digits = !c.empty() && c.size() < 19 &&
                          std::all_of(c.begin(), c.end(), [](char ch) { return ch >= '0' && ch <= '9'; });
      if (n != 2 || !digits)
        throw InputError(path, line, 0, "PLY element",
                         "'" + text + "' is not 'element <name> <count>' with a count below 1e18");
      // assimp reads faces against the vertices read before them; without them it spent 50 s
      // and 17 GB on a fuzzed file before saying so (an 'element vbspertex' in its place).
      elements.push_back({std::stoull(c), {}});
      if (std::string(name) == "vertex") seen_vertex = true;
      if (std::string(name) == "face" && !seen_vertex)
        throw InputError(path, line, 0, "PLY element",
                         "'" + text + "' comes before any 'element vertex' (the vertices must come first)");
      if (!size_error && std::stoull(c) > file_size)
        throw InputError(path, line, 0, "PLY element",
                         "'" + text + "' declares more " + name + " elements than the file's " +
                             std::to_string(file_size) + " bytes can hold");
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
    if ((*seen_mesh)[mi]) name += "#" + std::to_string(out->group_names.size());
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
      while (i < head.size() && (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n'))
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
                       "count '" + number + "' is more than the file's " + std::to_string(file_size) +
                           " bytes can hold");
    i = j;
    next();
  }
}

}  // namespace

ImportedPart readPartMesh(const std::string& path, const PartImportOptions& options) {
  ImportedPart part;
  part.format = lowerExtension(path);
  static const char* kFormats[] = {"stl", "obj", "ply", "off", "3mf", "gltf", "glb"};
  if (std::find_if(std::begin(kFormats), std::end(kFormats),
                   [&](const char* f) { return part.format == f; }) == std::end(kFormats))
    throw InputError(path, 0, 0, "mesh",
                     "unsupported part format '." + part.format +
                         "' (use .stl, .obj, .ply, .off, .3mf, .gltf or .glb)");
  if (!std::filesystem::is_regular_file(path))
    throw InputError(path, 0, 0, "mesh", "cannot open the file");

  part.units = options.units.empty() ? ((part.format == "gltf" || part.format == "glb") ? "m" : "mm")
                                     : options.units;
  double scale;
  if (part.units == "mm") scale = 1.0;
  else if (part.units == "inch" || part.units == "in") scale = 25.4;
  else if (part.units == "m") scale = 1000.0;
  else
    throw InputError(path, 0, 0, "units", "unknown length unit '" + part.units +
                                              "' (use mm, inch or m)");

  if (part.format == "ply") checkPlyHeader(path);
  if (part.format == "off") checkOffHeader(path);
  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  // Read and validated first, triangulated after: Debian's assimp 5.2 aborts the process (an
  // ai_assert in its TriangulateProcess) on a face without vertices, which a malformed PLY makes
  // (found by the mesh fuzz harness), so such faces are refused before triangulating.
  // An OBJ is handed over from memory with a zero byte after it: Debian's assimp 5.2 parses
  // numbers with strtol on its own copy of the file, which has no terminating zero, so a file
  // ending in digits would be read past its end (the mesh fuzz harness,
  // tests/fuzz/mesh_corpus/obj_strtol_unterminated).
  const aiScene* scene = nullptr;
  if (part.format == "obj") {
    std::string text = readFile(path);
    text.push_back('\n');
    text.push_back('\0');
    scene = importer.ReadFileFromMemory(text.data(), text.size(), aiProcess_ValidateDataStructure, "obj");
  } else {
    scene = importer.ReadFile(path, aiProcess_ValidateDataStructure);
  }
  auto unreadable = [&] {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "not a readable mesh";
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
  if (raw.faces.empty()) throw InputError(path, 0, 0, "mesh", "the file holds no triangles");
  for (auto& v : raw.vertices) v = options.w_T_file * (scale * v);
  // A vertex far beyond any part (a corrupt or mis-scaled file) would make the sampling and
  // the sweeps run for hours: parts lie within 1e5 mm of the part frame.
  for (size_t i = 0; i < raw.vertices.size(); ++i)
    if (!raw.vertices[i].allFinite() || raw.vertices[i].cwiseAbs().maxCoeff() > 1e5) {
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
  std::string out;
  out += "ply\nformat binary_little_endian 1.0\ncomment tolver swept surface, mm, part frame\n";
  out += "element vertex " + std::to_string(points.size()) + "\n";
  out += "property float x\nproperty float y\nproperty float z\n";
  out += "property float " + scalar_name + "\n";
  out += "element face " + std::to_string(faces.size()) + "\n";
  out += "property list uchar int vertex_indices\nend_header\n";
  auto put = [&](const void* p, size_t n) { out.append(static_cast<const char*>(p), n); };
  for (size_t i = 0; i < points.size(); ++i) {
    const float v[4] = {static_cast<float>(points[i].x()), static_cast<float>(points[i].y()),
                        static_cast<float>(points[i].z()), static_cast<float>(scalar[i])};
    put(v, sizeof v);
  }
  for (const auto& f : faces) {
    const unsigned char three = 3;
    put(&three, 1);
    const int32_t idx[3] = {f[0], f[1], f[2]};
    put(idx, sizeof idx);
  }
  writeFileAtomically(path, out);
}

void writeVtpWithScalars(
    const std::string& path, const std::vector<Eigen::Vector3d>& points,
    const std::vector<Eigen::Vector3i>& faces,
    const std::vector<std::pair<std::string, const std::vector<double>*>>& scalars) {
  vtkNew<vtkPoints> pts;
  pts->SetDataTypeToDouble();
  pts->SetNumberOfPoints(static_cast<vtkIdType>(points.size()));
  for (size_t i = 0; i < points.size(); ++i)
    pts->SetPoint(static_cast<vtkIdType>(i), points[i].data());
  vtkNew<vtkCellArray> cells;
  for (const auto& f : faces) {
    const vtkIdType ids[3] = {f[0], f[1], f[2]};
    cells->InsertNextCell(3, ids);
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(pts);
  poly->SetPolys(cells);
  for (const auto& [name, values] : scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfValues(static_cast<vtkIdType>(values->size()));
    for (size_t i = 0; i < values->size(); ++i) a->SetValue(static_cast<vtkIdType>(i), (*values)[i]);
    poly->GetPointData()->AddArray(a);
  }
  OutputSet out;
  out.addWritten(path, [&](const std::string& tmp) {
    vtkNew<vtkXMLPolyDataWriter> writer;
    writer->SetFileName(tmp.c_str());
    writer->SetInputData(poly);
    // Raw appended binary without compression: zlib took most of the writing time and saved
    // little (doubles compress poorly); ParaView and VTK read it as they read the compressed form.
    writer->SetDataModeToAppended();
    writer->EncodeAppendedDataOff();
    writer->SetCompressorTypeToNone();
    return writer->Write() == 1;
  });
  out.commit();
}

}  // namespace tolver
