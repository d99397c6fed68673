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

// Starts what ensureDisplay() needs without waiting for it: a command that will render calls it
// first, so that the server's start (0.1-0.2 s) overlaps its work. ensureDisplay() still decides.
void startDisplay();

// Keeps the GL driver Mesa loaded for the first render (its *_dri.so) in the process: Mesa's libGL
// unloads it when a context ends and loads it again for the next image (each map, chart and view
// of a report), and LeakSanitizer cannot name the allocations of a library that is gone. Call
// after a render; pins each driver once (RTLD_NODELETE).
void keepGlDriverLoaded();

}  // namespace tolver
