// STEP parts: the checks and the child process here; OpenCASCADE's reading in the tolver_occt
// module (io/mesh/step_reader_occt.cpp), opened in the child.
#include "io/mesh/step_file.h"

#include <filesystem>

#include "core/numerics/lazy_module.h"
#include "io/common/child_process.h"
#include "io/common/io_error.h"
#include "io/mesh/mesh_bytes.h"

namespace tolver {
namespace {

bool takePart(ByteReader& r, StepPart* p) {
  if (!takeMesh(r, &p->mesh)) return false;
  uint64_t n = 0;
  if (!r.takeCount(&n, 8)) return false;
  p->faces.resize(n);
  for (StepFace& f : p->faces)
    if (!r.take(&f.entity) || !r.takeString(&f.name) || !r.takeString(&f.colour) ||
        !r.take(&f.area_mm2))
      return false;
  for (std::string* s : {&p->schema, &p->system, &p->file_unit, &p->solid})
    if (!r.takeString(s)) return false;
  if (!r.takeCount(&n, 8)) return false;
  p->solids.resize(n);
  for (std::string& s : p->solids)
    if (!r.takeString(&s)) return false;
  Eigen::Vector3d lo, hi;
  if (!r.take(&p->area_mm2) || !r.take(&lo) || !r.take(&hi) || !r.take(&p->chordal_mm) ||
      !r.take(&p->angular_rad) || !r.take(&p->deflection_mm) || !r.takeCount(&n, 8))
    return false;
  p->box_mm = Eigen::AlignedBox3d(lo, hi);
  p->tolerances.resize(n);
  for (StepTolerance& t : p->tolerances) {
    uint64_t k = 0;
    if (!r.takeString(&t.type) || !r.takeString(&t.name) || !r.take(&t.value_mm) ||
        !r.take(&t.unequal) || !r.take(&t.offset_mm) || !r.takeCount(&k, sizeof(int)))
      return false;
    t.faces.resize(k);
    if (!r.takeBytes(t.faces.data(), k * sizeof(int))) return false;
  }
  if (!r.takeCount(&n, 8)) return false;
  p->notes.resize(n);
  for (std::string& s : p->notes)
    if (!r.takeString(&s)) return false;
  return true;
}

}  // namespace

StepPart readStepPart(const std::string& path, const StepReadOptions& options) {
  if (!std::filesystem::is_regular_file(path))
    throw InputError(path, 0, 0, "STEP", "cannot open the file");
  if (!(options.chordal_mm > 0) || !(options.angular_rad > 0))
    throw InputError(path, 0, 0, "STEP", "the tessellation's bounds must be positive");
  const std::string bytes = runInChildProcess(
      path, "OpenCASCADE",
      [&] { return moduleFunction<StepPartBytes>("tolver_occt", "stepPartBytes")(path, options); },
      options.in_process);
  StepPart part;
  ByteReader r(bytes);
  if (!takePart(r, &part))
    throw InputError(path, 0, 0, "STEP", "the STEP reader sent a damaged part");
  return part;
}

}  // namespace tolver
