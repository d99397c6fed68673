#pragma once
// OpenMesh reports a face it cannot add (a non-manifold edge or vertex) on its own error stream,
// omerr(), which writes to std::cerr. tolver names such a face itself (or keeps it as given), so
// that stream is turned off, once for the process, before OpenMesh is first used. (Swapping
// std::cerr's buffer around each call, as before, raced with any other thread writing to
// std::cerr, the CLI's progress among them, and with a second decimating thread.)

namespace tolver {

void quietOpenMesh();

}  // namespace tolver
