#include "io/report/offscreen_display.h"

#include <X11/Xlib.h>
#include <dlfcn.h>
#include <fcntl.h>
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

// The server forked and not yet waited for (forkXvfb).
struct Starting {
  pid_t pid = -1;
  int fd = -1;  // the read end of -displayfd's pipe
  std::string xvfb;
};

// Forks Xvfb without waiting for it. The child calls only what is safe after a fork in a process
// with threads (no allocation: its arguments are built before the fork).
bool forkXvfb(Starting* s, std::string* message) {
  s->xvfb = findXvfb();
  if (s->xvfb.empty()) {
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
  const std::string fd = std::to_string(fds[1]);
  const pid_t pid = fork();
  if (pid < 0) {
    close(fds[0]);
    close(fds[1]);
    *message = "cannot render images: fork() failed";
    return false;
  }
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);  // the server dies with tolver
    close(fds[0]);
    // Xvfb's own messages go nowhere: they are not tolver's output.
    const int devnull = open("/dev/null", O_WRONLY);
    if (devnull >= 0) {
      dup2(devnull, 1);
      dup2(devnull, 2);
    }
    execl(s->xvfb.c_str(), "Xvfb", "-displayfd", fd.c_str(), "-screen", "0", "1920x1200x24",
          "-nolisten", "tcp", "-noreset", static_cast<char*>(nullptr));
    _exit(127);
  }
  close(fds[1]);
  s->pid = pid;
  s->fd = fds[0];
  return true;
}

// Waits for the forked server's display number (at most 15 s) and points $DISPLAY at it.
bool finishXvfb(Starting* s, std::string* message) {
  std::string number;
  pollfd p{s->fd, POLLIN, 0};
  while (true) {
    if (poll(&p, 1, 15000) <= 0) break;
    char c;
    const ssize_t n = read(s->fd, &c, 1);
    if (n <= 0 || c == '\n') break;
    number += c;
  }
  close(s->fd);
  s->fd = -1;
  if (number.empty()) {
    kill(s->pid, SIGTERM);
    waitpid(s->pid, nullptr, 0);
    *message = "cannot render images: " + s->xvfb + " did not start";
    return false;
  }
  g_server = s->pid;
  std::atexit(stopServer);
  const std::string display = ":" + number;
  setenv("DISPLAY", display.c_str(), 1);
  if (!canOpen(display.c_str())) {
    *message = "cannot render images: the private X server " + display + " cannot be opened";
    return false;
  }
  return true;
}

std::mutex g_mutex;
int g_state = 0;  // 0 unknown, 2 starting, 1 ready, -1 failed
Starting g_starting;
std::string g_failure;

// Under g_mutex: from unknown to starting (or to ready: $DISPLAY opens; or failed).
void beginLocked() {
  if (g_state != 0) return;
  if (canOpen(std::getenv("DISPLAY")))
    g_state = 1;
  else
    g_state = forkXvfb(&g_starting, &g_failure) ? 2 : -1;
}

}  // namespace

void startDisplay() {
  std::lock_guard<std::mutex> lock(g_mutex);
  beginLocked();
}

bool ensureDisplay(std::string* message) {
  std::lock_guard<std::mutex> lock(g_mutex);
  beginLocked();
  if (g_state == 2) g_state = finishXvfb(&g_starting, &g_failure) ? 1 : -1;
  if (g_state < 0 && message) *message = g_failure;
  return g_state > 0;
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
