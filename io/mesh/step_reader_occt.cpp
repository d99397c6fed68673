// The OpenCASCADE module (libtolver_occt.so, core/numerics/lazy_module.h): a STEP part read and
// tessellated, sent back as bytes (io/mesh/step_file.cpp runs it in a child process).
#include "io/mesh/step_file.h"

// OpenCASCADE 7.6 (Debian 12's libocct-*-dev): this file alone includes it.
#include <APIHeaderSection_MakeHeader.hxx>
#include <BRepBndLib.hxx>
#include <BRepCheck.hxx>
#include <BRepCheck_Analyzer.hxx>
#include <BRepCheck_ListOfStatus.hxx>
#include <BRepCheck_Result.hxx>
#include <BRepGProp.hxx>
#include <BRepMesh_IncrementalMesh.hxx>
#include <BRep_Tool.hxx>
#include <Bnd_Box.hxx>
#include <GProp_GProps.hxx>
#include <Interface_EntityIterator.hxx>
#include <Interface_Graph.hxx>
#include <Interface_Static.hxx>
#include <Message.hxx>
#include <Message_Messenger.hxx>
#include <Poly_Triangulation.hxx>
#include <Quantity_Color.hxx>
#include <STEPCAFControl_Reader.hxx>
#include <STEPControl_Reader.hxx>
#include <ShapeFix_Shape.hxx>
#include <Standard_Failure.hxx>
#include <StepBasic_LengthMeasureWithUnit.hxx>
#include <StepBasic_MeasureValueMember.hxx>
#include <StepBasic_MeasureWithUnit.hxx>
#include <StepData_StepModel.hxx>
#include <StepDimTol_GeoTolAndGeoTolWthDatRefAndUneqDisGeoTol.hxx>
#include <StepDimTol_GeometricTolerance.hxx>
#include <StepDimTol_UnequallyDisposedGeometricTolerance.hxx>
#include <StepRepr_ReprItemAndMeasureWithUnit.hxx>
#include <StepShape_FaceSurface.hxx>
#include <TCollection_HAsciiString.hxx>
#include <TDF_Label.hxx>
#include <TDF_LabelSequence.hxx>
#include <TDataStd_Name.hxx>
#include <TDocStd_Document.hxx>
#include <TopExp.hxx>
#include <TopExp_Explorer.hxx>
#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TransferBRep.hxx>
#include <Transfer_TransientProcess.hxx>
#include <XCAFApp_Application.hxx>
#include <XCAFDimTolObjects_GeomToleranceObject.hxx>
#include <XCAFDoc_ColorTool.hxx>
#include <XCAFDoc_DimTolTool.hxx>
#include <XCAFDoc_DocumentTool.hxx>
#include <XCAFDoc_GeomTolerance.hxx>
#include <XCAFDoc_ShapeTool.hxx>
#include <XSControl_TransferReader.hxx>
#include <XSControl_WorkSession.hxx>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>
#include <type_traits>

#include "core/numerics/lazy_module.h"
#include "io/common/child_process.h"
#include "io/common/io_error.h"
#include "io/mesh/mesh_bytes.h"

namespace tolver::occt {
namespace {

std::string text(const Handle(TCollection_HAsciiString) & s) {
  return s.IsNull() ? std::string() : std::string(s->ToCString());
}

// A name as CAD systems leave it: "" and "NONE" (and their quoted forms) are no name.
std::string cadName(const std::string& raw) {
  std::string s = raw;
  while (!s.empty() && (s.back() == ' ' || s.back() == '\'')) s.pop_back();
  while (!s.empty() && (s.front() == ' ' || s.front() == '\'')) s.erase(0, 1);
  // OCCT names an unnamed label by its entry, "=>[0:1:1:2]".
  return (s == "NONE" || s == "none" || s == "$" || s.rfind("=>[", 0) == 0) ? std::string() : s;
}

std::string labelName(const TDF_Label& label) {
  Handle(TDataStd_Name) name;
  if (label.IsNull() || !label.FindAttribute(TDataStd_Name::GetID(), name)) return {};
  TCollection_AsciiString a(name->Get());
  return cadName(a.ToCString());
}

const char* toleranceType(XCAFDimTolObjects_GeomToleranceType t) {
  switch (t) {
    case XCAFDimTolObjects_GeomToleranceType_Angularity:
      return "angularity";
    case XCAFDimTolObjects_GeomToleranceType_CircularRunout:
      return "circular runout";
    case XCAFDimTolObjects_GeomToleranceType_CircularityOrRoundness:
      return "circularity";
    case XCAFDimTolObjects_GeomToleranceType_Coaxiality:
      return "coaxiality";
    case XCAFDimTolObjects_GeomToleranceType_Concentricity:
      return "concentricity";
    case XCAFDimTolObjects_GeomToleranceType_Cylindricity:
      return "cylindricity";
    case XCAFDimTolObjects_GeomToleranceType_Flatness:
      return "flatness";
    case XCAFDimTolObjects_GeomToleranceType_Parallelism:
      return "parallelism";
    case XCAFDimTolObjects_GeomToleranceType_Perpendicularity:
      return "perpendicularity";
    case XCAFDimTolObjects_GeomToleranceType_Position:
      return "position";
    case XCAFDimTolObjects_GeomToleranceType_ProfileOfLine:
      return "profile of a line";
    case XCAFDimTolObjects_GeomToleranceType_ProfileOfSurface:
      return "profile of a surface";
    case XCAFDimTolObjects_GeomToleranceType_Straightness:
      return "straightness";
    case XCAFDimTolObjects_GeomToleranceType_Symmetry:
      return "symmetry";
    case XCAFDimTolObjects_GeomToleranceType_TotalRunout:
      return "total runout";
    default:
      return "unknown";
  }
}

// mm per unit of the file's length unit as FileUnits names it; 0 when unknown.
double mmPer(std::string unit) {
  std::transform(unit.begin(), unit.end(), unit.begin(), ::toupper);
  if (unit == "MM" || unit == "MILLIMETRE" || unit == "MILLIMETER") return 1.0;
  if (unit == "INCH" || unit == "IN") return 25.4;
  if (unit == "M" || unit == "METRE" || unit == "METER") return 1000.0;
  if (unit == "CM" || unit == "CENTIMETRE" || unit == "CENTIMETER") return 10.0;
  if (unit == "FT" || unit == "FOOT") return 304.8;
  if (unit == "UM" || unit == "MICROMETRE" || unit == "MICROMETER") return 1e-3;
  return 0.0;
}

// A solid (or, in a file of surfaces, a shell) of the file with the names a user may call it by.
struct Candidate {
  TopoDS_Shape shape;  // located in the file's frame
  std::string product, instance;
  bool solid = false;
  std::string name() const { return instance.empty() ? product : instance; }
};

// Names CAD systems give a representation rather than a part (Creo's "SOLID" in a part of an
// assembly): the enclosing product's name serves instead.
bool genericName(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), ::toupper);
  return s.empty() || s == "SOLID" || s == "COMPOUND" || s == "SHELL" || s == "OPEN_SHELL" ||
         s == "CLOSED_SHELL" || s == "MANIFOLD_SOLID_BREP" || s == "BREP" || s == "BODY";
}

// Walks the XCAF tree below `label`; a component without a name of its own (Creo's solid inside
// a part assembly) keeps the enclosing component's and product's names.
void collectCandidates(const TDF_Label& label, const TopLoc_Location& loc,
                       const std::string& instance, const std::string& parent_product,
                       std::vector<Candidate>* out) {
  std::string product = labelName(label);
  if (genericName(product)) product = parent_product;
  if (XCAFDoc_ShapeTool::IsAssembly(label)) {
    TDF_LabelSequence components;
    XCAFDoc_ShapeTool::GetComponents(label, components);
    for (Standard_Integer i = 1; i <= components.Length(); ++i) {
      TDF_Label referred;
      if (!XCAFDoc_ShapeTool::GetReferredShape(components(i), referred)) continue;
      std::string name = labelName(components(i));
      if (genericName(name)) name = instance;
      collectCandidates(referred, loc * XCAFDoc_ShapeTool::GetLocation(components(i)), name,
                        product, out);
    }
    return;
  }
  const TopoDS_Shape shape = XCAFDoc_ShapeTool::GetShape(label);
  if (shape.IsNull()) return;
  std::vector<TopoDS_Shape> bodies;
  for (TopExp_Explorer e(shape, TopAbs_SOLID); e.More(); e.Next()) bodies.push_back(e.Current());
  const bool solid = !bodies.empty();
  if (bodies.empty())  // a file of surfaces: its shells, or its faces as one body
    for (TopExp_Explorer e(shape, TopAbs_SHELL); e.More(); e.Next()) bodies.push_back(e.Current());
  if (bodies.empty() && TopExp_Explorer(shape, TopAbs_FACE).More()) bodies.push_back(shape);
  for (size_t k = 0; k < bodies.size(); ++k) {
    const std::string suffix = bodies.size() > 1 ? "#" + std::to_string(k + 1) : "";
    Candidate c;
    c.shape = bodies[k].Moved(loc);
    c.product = (product.empty() ? std::string(solid ? "solid" : "shell") : product) + suffix;
    c.instance = instance.empty() ? std::string() : instance + suffix;
    c.solid = solid;
    out->push_back(c);
  }
}

// The candidates' names for a message, quoted: each once, with its count when repeated.
std::string distinctNames(const std::vector<Candidate>& candidates) {
  std::vector<std::string> names;
  std::vector<int> counts;
  for (const Candidate& c : candidates) {
    const auto at = std::find(names.begin(), names.end(), c.name());
    if (at == names.end()) {
      names.push_back(c.name());
      counts.push_back(1);
    } else {
      ++counts[at - names.begin()];
    }
  }
  for (size_t i = 0; i < names.size(); ++i)
    names[i] = "'" + (names[i].empty() ? std::string("(unnamed)") : names[i]) + "'" +
               (counts[i] > 1 ? " (" + std::to_string(counts[i]) + " instances)" : "");
  std::string s;
  for (size_t i = 0; i < names.size() && i < 12; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > 12) s += ", ...";
  return s;
}

StepPart readInProcess(const std::string& path, const StepReadOptions& o) {
  // Library code never prints: OCCT's messages (the reader's trace, warnings) go nowhere.
  Message::DefaultMessenger()->ChangePrinters().Clear();
  StepPart part;
  STEPCAFControl_Reader reader;
  reader.SetColorMode(true);
  reader.SetNameMode(true);
  reader.SetGDTMode(true);
  reader.SetLayerMode(false);
  const IFSelect_ReturnStatus status = reader.ReadFile(path.c_str());
  if (status != IFSelect_RetDone)
    throw InputError(path, 0, 0, "STEP",
                     status == IFSelect_RetVoid
                         ? "OCCT's STEP reader found no entity in it (not a STEP file?)"
                         : "OCCT's STEP reader could not read it (a damaged or not ISO 10303-21 "
                           "file)");
  Handle(StepData_StepModel) model = reader.ChangeReader().StepModel();
  APIHeaderSection_MakeHeader header(model);
  if (header.HasFn()) part.system = cadName(text(header.OriginatingSystem()));
  if (header.HasFs() && header.NbSchemaIdentifiers() > 0)
    part.schema = text(header.SchemaIdentifiersValue(1));
  TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
  reader.ChangeReader().FileUnits(lengths, angles, solid_angles);
  if (lengths.Length() > 0) part.file_unit = lengths(1).ToCString();
  for (Standard_Integer i = 2; i <= lengths.Length(); ++i)
    if (lengths(i) != lengths(1))
      part.notes.push_back(std::string("the file mixes length units (") + lengths(1).ToCString() +
                           ", " + lengths(i).ToCString() + "): each converted to mm");

  Handle(XCAFApp_Application) app = XCAFApp_Application::GetApplication();
  Handle(TDocStd_Document) doc;
  app->NewDocument("MDTV-XCAF", doc);
  XCAFDoc_DocumentTool::SetLengthUnit(doc, 1.0, UnitsMethods_LengthUnit_Millimeter);
  if (!reader.Transfer(doc))
    throw InputError(path, 0, 0, "STEP", "OCCT could not transfer its shapes (no B-rep read)");
  Handle(XCAFDoc_ShapeTool) shapes = XCAFDoc_DocumentTool::ShapeTool(doc->Main());
  Handle(XCAFDoc_ColorTool) colours = XCAFDoc_DocumentTool::ColorTool(doc->Main());

  // The solid to read.
  std::vector<Candidate> candidates;
  TDF_LabelSequence free;
  shapes->GetFreeShapes(free);
  for (Standard_Integer i = 1; i <= free.Length(); ++i)
    collectCandidates(free(i), TopLoc_Location(), "", "", &candidates);
  if (candidates.empty())
    throw InputError(path, 0, 0, "STEP", "the file holds no solid, shell or face");
  // A solid is the part; shells beside it (construction or PMI surfaces) are not.
  const size_t n_solids = static_cast<size_t>(std::count_if(
      candidates.begin(), candidates.end(), [](const Candidate& c) { return c.solid; }));
  if (n_solids > 0 && n_solids < candidates.size()) {
    part.notes.push_back(std::to_string(candidates.size() - n_solids) +
                         " shell(s) or free faces beside the solid(s) left out");
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [](const Candidate& c) { return !c.solid; }),
                     candidates.end());
  }
  for (const Candidate& c : candidates) part.solids.push_back(c.name());
  const Candidate* chosen = nullptr;
  if (!o.part_name.empty()) {
    for (const Candidate& c : candidates)
      if (c.product == o.part_name || c.instance == o.part_name) {
        if (chosen) {
          part.notes.push_back("'" + o.part_name + "' names more than one solid: the first read");
          break;
        }
        chosen = &c;
      }
    if (!chosen)
      throw InputError(
          path, 0, 0, "part_name",
          "no solid named '" + o.part_name + "' (its solids: " + distinctNames(candidates) + ")");
  } else if (candidates.size() == 1) {
    chosen = &candidates[0];
  } else {
    throw InputError(path, 0, 0, "STEP",
                     "the file holds " + std::to_string(candidates.size()) + " solids (" +
                         distinctNames(candidates) + "): choose one with --part-name");
  }
  part.solid = chosen->name();
  TopoDS_Shape shape = chosen->shape;

  // OCCT's own checks; ShapeFix where they fail, and a refusal when it cannot repair.
  {
    BRepCheck_Analyzer check(shape);
    if (!check.IsValid()) {
      ShapeFix_Shape fix(shape);
      fix.Perform();
      BRepCheck_Analyzer again(fix.Shape());
      if (!again.IsValid()) {
        std::string what = "invalid B-rep";
        for (TopExp_Explorer e(fix.Shape(), TopAbs_FACE); e.More(); e.Next()) {
          const Handle(BRepCheck_Result)& r = again.Result(e.Current());
          if (r.IsNull()) continue;
          for (BRepCheck_ListIteratorOfListOfStatus it(r->Status()); it.More(); it.Next())
            if (it.Value() != BRepCheck_NoError) {
              std::ostringstream s;
              BRepCheck::Print(it.Value(), s);
              what = "a face fails BRepCheck (" + s.str() + ")";
              break;
            }
          if (what != "invalid B-rep") break;
        }
        while (!what.empty() && (what.back() == '\n' || what.back() == ' ')) what.pop_back();
        throw InputError(path, 0, 0, "STEP",
                         "OCCT's BRepCheck finds the solid '" + part.solid + "' invalid: " + what +
                             ", and ShapeFix does not repair it");
      }
      part.notes.push_back(
          "OCCT's BRepCheck found the B-rep invalid; ShapeFix repaired it "
          "(face entity numbers may be lost where faces were rebuilt)");
      shape = fix.Shape();
    }
  }

  // Each face's entity number and name in the file.
  std::map<const TopoDS_TShape*, std::pair<int, std::string>> entity_of;
  {
    Handle(Transfer_TransientProcess) tp =
        reader.ChangeReader().WS()->TransferReader()->TransientProcess();
    for (Standard_Integer i = 1; i <= model->NbEntities(); ++i) {
      Handle(Standard_Transient) ent = model->Value(i);
      if (!ent->IsKind(STANDARD_TYPE(StepShape_FaceSurface))) continue;
      const TopoDS_Shape s = TransferBRep::ShapeResult(tp, ent);
      if (s.IsNull() || s.ShapeType() != TopAbs_FACE) continue;
      Handle(StepShape_FaceSurface) face = Handle(StepShape_FaceSurface)::DownCast(ent);
      entity_of[s.TShape().get()] = {model->IdentLabel(ent), cadName(text(face->Name()))};
    }
  }

  // The tessellation within the chordal and angular bounds.
  part.chordal_mm = o.chordal_mm;
  part.angular_rad = o.angular_rad;
  BRepMesh_IncrementalMesh mesher(shape, o.chordal_mm, false, o.angular_rad, true);
  if (!mesher.IsDone()) throw InputError(path, 0, 0, "STEP", "OCCT's BRepMesh failed on it");
  TopTools_IndexedMapOfShape faces;
  TopExp::MapShapes(shape, TopAbs_FACE, faces);
  TriangleMesh& mesh = part.mesh;
  std::map<const TopoDS_TShape*, int> group_of;
  std::map<std::string, int> used_names;
  for (Standard_Integer fi = 1; fi <= faces.Extent(); ++fi) {
    const TopoDS_Face face = TopoDS::Face(faces(fi));
    const int group = static_cast<int>(part.faces.size());
    StepFace info;
    const auto it = entity_of.find(face.TShape().get());
    if (it != entity_of.end()) {
      info.entity = it->second.first;
      info.name = it->second.second;
    }
    Quantity_Color colour;
    if (colours->GetColor(face, XCAFDoc_ColorSurf, colour) ||
        colours->GetColor(face, XCAFDoc_ColorGen, colour))
      info.colour = Quantity_Color::ColorToHex(colour).ToCString();
    std::transform(info.colour.begin(), info.colour.end(), info.colour.begin(), ::tolower);
    GProp_GProps props;  // adaptive to 1e-7, as Draw's sprops
    BRepGProp::SurfaceProperties(face, props, 1e-7);
    info.area_mm2 = props.Mass();
    part.area_mm2 += info.area_mm2;
    std::string gname =
        info.entity > 0 ? "face #" + std::to_string(info.entity) : "face " + std::to_string(fi);
    if (used_names[gname]++) gname += " (" + std::to_string(used_names[gname]) + ")";
    mesh.group_names.push_back(gname);
    std::vector<std::string> aliases;
    if (!info.name.empty()) aliases.push_back(info.name);
    if (!info.colour.empty()) aliases.push_back("colour " + info.colour);
    mesh.group_aliases.push_back(aliases);
    group_of[face.TShape().get()] = group;
    part.faces.push_back(info);

    TopLoc_Location loc;
    const Handle(Poly_Triangulation)& tri = BRep_Tool::Triangulation(face, loc);
    if (tri.IsNull() || tri->NbTriangles() == 0) {
      if (info.area_mm2 > 1e-6)
        part.notes.push_back("BRepMesh left " + gname + " (" + std::to_string(info.area_mm2) +
                             " mm^2) without triangles: it is not checked");
      continue;
    }
    // BRepMesh's own measure of the distance its facets keep from the face.
    part.deflection_mm = std::max(part.deflection_mm, tri->Deflection());
    const gp_Trsf trsf = loc.Transformation();
    const int base = static_cast<int>(mesh.vertices.size());
    for (Standard_Integer n = 1; n <= tri->NbNodes(); ++n) {
      const gp_Pnt p = tri->Node(n).Transformed(trsf);
      mesh.vertices.emplace_back(p.X(), p.Y(), p.Z());
    }
    const bool reversed = face.Orientation() == TopAbs_REVERSED;
    for (Standard_Integer t = 1; t <= tri->NbTriangles(); ++t) {
      Standard_Integer a, b, c;
      tri->Triangle(t).Get(a, b, c);
      if (reversed) std::swap(b, c);
      mesh.faces.emplace_back(base + a - 1, base + b - 1, base + c - 1);
      mesh.face_group.push_back(group);
    }
  }
  Bnd_Box box;
  BRepBndLib::AddOptimal(shape, box, false, false);
  if (!box.IsVoid()) {
    double x0, y0, z0, x1, y1, z1;
    box.Get(x0, y0, z0, x1, y1, z1);
    part.box_mm = Eigen::AlignedBox3d(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1));
  }

  // Semantic PMI: geometric tolerances and the faces they apply to.
  // OCCT 7.6's XCAF leaves a tolerance's value 0 when the file gives its magnitude as a complex
  // entity (LENGTH_MEASURE_WITH_UNIT with MEASURE_REPRESENTATION_ITEM, as AP242 writers do) and
  // does not keep unequally disposed zones: both are read from the STEP entities, by name.
  struct Read {
    double value_mm = 0, offset_mm = 0;
    bool unequal = false;
    int count = 0;
  };
  std::map<std::string, Read> read_of;
  const double unit_mm = mmPer(part.file_unit) > 0 ? mmPer(part.file_unit) : 1.0;
  const Interface_Graph& graph = reader.ChangeReader().WS()->Graph();
  for (Standard_Integer i = 1; i <= model->NbEntities(); ++i) {
    Handle(StepDimTol_GeometricTolerance) gt =
        Handle(StepDimTol_GeometricTolerance)::DownCast(model->Value(i));
    if (gt.IsNull()) continue;
    Read& r = read_of[cadName(text(gt->Name()))];
    ++r.count;
    if (!gt->Magnitude().IsNull()) r.value_mm = gt->Magnitude()->ValueComponent() * unit_mm;
    for (Interface_EntityIterator it = graph.Shareds(gt); it.More(); it.Next()) {
      Handle(StepRepr_ReprItemAndMeasureWithUnit) m =
          Handle(StepRepr_ReprItemAndMeasureWithUnit)::DownCast(it.Value());
      if (r.value_mm == 0 && !m.IsNull() && !m->GetMeasureWithUnit().IsNull())
        r.value_mm = m->GetMeasureWithUnit()->ValueComponent() * unit_mm;
    }
    Handle(StepDimTol_UnequallyDisposedGeometricTolerance) ud =
        Handle(StepDimTol_UnequallyDisposedGeometricTolerance)::DownCast(gt);
    Handle(StepDimTol_GeoTolAndGeoTolWthDatRefAndUneqDisGeoTol) ud_complex =
        Handle(StepDimTol_GeoTolAndGeoTolWthDatRefAndUneqDisGeoTol)::DownCast(gt);
    if (!ud_complex.IsNull()) ud = ud_complex->GetUnequallyDisposedGeometricTolerance();
    if (!ud.IsNull() && !ud->Displacement().IsNull()) {
      r.unequal = true;
      r.offset_mm = ud->Displacement()->ValueComponent() * unit_mm;
    }
  }
  Handle(XCAFDoc_DimTolTool) dimtol = XCAFDoc_DocumentTool::DimTolTool(doc->Main());
  TDF_LabelSequence tolerances;
  dimtol->GetGeomToleranceLabels(tolerances);
  for (Standard_Integer i = 1; i <= tolerances.Length(); ++i) {
    Handle(XCAFDoc_GeomTolerance) attr;
    if (!tolerances(i).FindAttribute(XCAFDoc_GeomTolerance::GetID(), attr)) continue;
    Handle(XCAFDimTolObjects_GeomToleranceObject) object = attr->GetObject();
    if (object.IsNull()) continue;
    StepTolerance t;
    t.type = toleranceType(object->GetType());
    t.value_mm = object->GetValue();
    const std::string name = cadName(text(object->GetSemanticName()));
    const auto read = read_of.find(name);
    if (read != read_of.end() && read->second.count == 1) {
      if (t.value_mm == 0) t.value_mm = read->second.value_mm;
      t.unequal = read->second.unequal;
      t.offset_mm = read->second.offset_mm;
    }
    t.name = name;
    TDF_LabelSequence first, second;
    dimtol->GetRefShapeLabel(tolerances(i), first, second);
    for (Standard_Integer k = 1; k <= first.Length(); ++k) {
      const TopoDS_Shape s = XCAFDoc_ShapeTool::GetShape(first(k));
      if (s.IsNull()) continue;
      for (TopExp_Explorer e(s, TopAbs_FACE); e.More(); e.Next()) {
        const auto g = group_of.find(e.Current().TShape().get());
        if (g != group_of.end() &&
            std::find(t.faces.begin(), t.faces.end(), g->second) == t.faces.end())
          t.faces.push_back(g->second);
      }
    }
    std::sort(t.faces.begin(), t.faces.end());
    part.tolerances.push_back(t);
  }
  return part;
}

void putPart(ByteWriter& w, const StepPart& p) {
  putMesh(w, p.mesh);
  w.put<uint64_t>(p.faces.size());
  for (const StepFace& f : p.faces) {
    w.put(f.entity);
    w.putString(f.name);
    w.putString(f.colour);
    w.put(f.area_mm2);
  }
  for (const std::string* s : {&p.schema, &p.system, &p.file_unit, &p.solid}) w.putString(*s);
  w.put<uint64_t>(p.solids.size());
  for (const std::string& s : p.solids) w.putString(s);
  w.put(p.area_mm2);
  w.put(p.box_mm.min());
  w.put(p.box_mm.max());
  w.put(p.chordal_mm);
  w.put(p.angular_rad);
  w.put(p.deflection_mm);
  w.put<uint64_t>(p.tolerances.size());
  for (const StepTolerance& t : p.tolerances) {
    w.putString(t.type);
    w.putString(t.name);
    w.put(t.value_mm);
    w.put(t.unequal);
    w.put(t.offset_mm);
    w.put<uint64_t>(t.faces.size());
    w.putBytes(t.faces.data(), t.faces.size() * sizeof(int));
  }
  w.put<uint64_t>(p.notes.size());
  for (const std::string& s : p.notes) w.putString(s);
}

}  // namespace

// The part, as the bytes step_file.cpp's takePart reads; OCCT's exceptions as InputError.
std::string stepPartBytes(const std::string& path, const StepReadOptions& options) {
  ByteWriter w;
  try {
    putPart(w, readInProcess(path, options));
  } catch (const Standard_Failure& e) {
    throw InputError(path, 0, 0, "STEP",
                     std::string("OpenCASCADE raised ") + e.DynamicType()->Name() + " (" +
                         (e.GetMessageString() ? e.GetMessageString() : "") +
                         ") reading it: a damaged file?");
  }
  return std::move(w.bytes());
}
static_assert(std::is_same_v<decltype(stepPartBytes), StepPartBytes>);

}  // namespace tolver::occt

TOLVER_MODULE_EXPORTS({"stepPartBytes", reinterpret_cast<void*>(&tolver::occt::stepPartBytes)})
