#include "geometry/openmesh_quiet.h"

#include <OpenMesh/Core/System/omstream.hh>

namespace tolver {

void quietOpenMesh() {
  static const bool quiet = [] {  // once, on whichever thread comes first
    omerr().disable();            // OpenMesh declares it at global scope
    return true;
  }();
  (void)quiet;
}

}  // namespace tolver
