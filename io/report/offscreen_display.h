#pragma once
// Off-screen rendering needs an X display: Debian 12's VTK renders through GLX only (it is built
// with neither OSMesa nor EGL). ensureDisplay() uses $DISPLAY when it can be opened; otherwise it
// starts a private virtual X server (Xvfb, with -displayfd so it picks a free display number),
// points $DISPLAY at it, and stops it when the process exits. No window is ever shown.
#include <string>

namespace tolver {

// True when rendering can go ahead. On false, *message says what is missing and what to install.
// Thread-safe; starts at most one server per process.
bool ensureDisplay(std::string* message);

}  // namespace tolver
