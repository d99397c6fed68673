// The measured-part sample (samples/measured/): the sculptured part's finish as a three-axis
// ball-end program, cut by the independent machining simulation (tests/independent_machining.h)
// with a tool 10 um longer than preset, and measured at 1 000 places twice each (2 000 points)
// with 0.5 um of probe noise: the repeats test the model's adequacy.
//   make_measured_sample <source dir> <output dir> [points] [seed]
#include <cstdio>
#include <filesystem>
#include <string>

#include "io/common/io_error.h"
#include "io/mesh/mesh_file.h"
#include "tests/independent_machining.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: make_measured_sample <source dir> <output dir> [points] [seed]\n");
    return 2;
  }
  const std::string src = argv[1], out = argv[2];
  const int points = argc > 3 ? std::stoi(argv[3]) : 2000;
  const unsigned seed = argc > 4 ? static_cast<unsigned>(std::stoul(argv[4])) : 1u;
  std::filesystem::create_directories(out);
  const std::vector<indep_cut::Cl> cl =
      indep_cut::readGotos(src + "/samples/sculptured_finish.apt");
  const tolver::TriangleMesh mesh = tolver::readPartMesh(src + "/samples/sculptured_part.obj").mesh;
  indep_cut::Effect hidden;
  hidden.length_error_mm = 0.010;
  const indep_cut::Simulator sim(indep_cut::upright(cl, 5.0), 5.0, hidden);
  tolver::writeFileAtomically(out + "/sculptured_3axis.apt", indep_cut::threeAxisProgram(cl, 5.0));
  tolver::writeFileAtomically(out + "/cmm_points.csv",
                              "# made by tools/make_measured_sample.cpp: the independent machining "
                              "simulation, one hidden process effect, 0.5 um probe noise\n" +
                                  indep_cut::measuredCsv(mesh, sim, points, seed, 0.5e-3, 2));
  std::printf("wrote %s/sculptured_3axis.apt and %s/cmm_points.csv (%d points)\n", out.c_str(),
              out.c_str(), points);
  return 0;
}
