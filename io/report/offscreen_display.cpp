#include "io/report/offscreen_display.h"

#include <X11/Xlib.h>
#include <dlfcn.h>
#include <link.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>

namespace tolver {
namespace {

pid_t g_server = -1;

void stopServer() {
  if (g_server > 0) {
    kill(g_server, SIGTERM);
    waitpid(g_server, nullptr, 0);
    g_server = -1;
  }
}

int pinDriver(struct dl_phdr_info* info, size_t, void*) {
  const std::string name = info->dlpi_name ? info->dlpi_name : "";
  if (name.size() > 7 && name.compare(name.size() - 7, 7, "_dri.so") == 0)
    dlopen(name.c_str(), RTLD_NOW | RTLD_NOLOAD | RTLD_NODELETE);  // the handle is kept for good
  return 0;
}

bool canOpen(const char* display) {
  if (!display || !*display) return false;
  Display* d = XOpenDisplay(display);
  if (!d) return false;
  XCloseDisplay(d);
  return true;
}

std::string findXvfb() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = dirs.find(':', start);
    const std::string dir =
        dirs.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const std::string candidate = (dir.empty() ? "." : dir) + "/Xvfb";
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return access("/usr/bin/Xvfb", X_OK) == 0 ? "/usr/bin/Xvfb" : "";
}

bool startXvfb(std::string* message) {
  const std::string xvfb = findXvfb();
  if (xvfb.empty()) {
    *message =
        "cannot render images: no X display ($DISPLAY) and no Xvfb to start one; install "
        "it (sudo apt-get install xvfb, or scripts/install_deps.sh), or pass --no-images";
    return false;
  }
  int fds[2];
  if (pipe(fds) != 0) {
    *message = "cannot render images: pipe() failed";
    return false;
  }
  const pid_t pid = fork();
  if (pid < 0) {
    *message = "cannot render images: fork() failed";
    return false;
  }
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);  // the server dies with tolver
    close(fds[0]);
    const std::string fd = std::to_string(fds[1]);
    // Xvfb's own messages go nowhere: they are not tolver's output.
    FILE* devnull = std::fopen("/dev/null", "w");
    if (devnull) {
      dup2(fileno(devnull), 1);
      dup2(fileno(devnull), 2);
    }
    execl(xvfb.c_str(), "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1920x1200x24",
          "-nolisten", "tcp", "-noreset", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  std::string number;
  pollfd p{fds[0], POLLIN, 0};
  while (true) {
    if (poll(&p, 1, 15000) <= 0) break;
    char c;
    const ssize_t n = read(fds[0], &c, 1);
    if (n <= 0 || c == '\n') break;
    number += c;
  }
  close(fds[0]);
  if (number.empty()) {
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
    *message = "cannot render images: " + xvfb + " did not start";
    return false;
  }
  g_server = pid;
  std::atexit(stopServer);
  const std::string display = ":" + number;
  setenv("DISPLAY", display.c_str(), 1);
  if (!canOpen(display.c_str())) {
    *message = "cannot render images: the private X server " + display + " cannot be opened";
    return false;
  }
  return true;
}

}  // namespace

bool ensureDisplay(std::string* message) {
  static std::mutex mutex;
  static int state = 0;  // 0 unknown, 1 ready, -1 failed
  static std::string failure;
  std::lock_guard<std::mutex> lock(mutex);
  if (state == 0) {
    if (canOpen(std::getenv("DISPLAY")))
      state = 1;
    else
      state = startXvfb(&failure) ? 1 : -1;
  }
  if (state < 0 && message) *message = failure;
  return state > 0;
}

void keepGlDriverLoaded() {
  static std::mutex m;
  static bool pinned = false;
  std::lock_guard<std::mutex> lock(m);
  if (pinned) return;
  dl_iterate_phdr(pinDriver, nullptr);
  pinned = true;
}

}  // namespace tolver
