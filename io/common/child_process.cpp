#include "io/common/child_process.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "io/common/io_error.h"

namespace tolver {

bool ByteReader::takeBytes(void* p, size_t n) {
  if (bytes_.size() - at_ < n) return false;
  if (n > 0) std::memcpy(p, bytes_.data() + at_, n);
  at_ += n;
  return true;
}

bool ByteReader::takeString(std::string* s) {
  uint64_t n = 0;
  if (!takeCount(&n, 1)) return false;
  s->assign(bytes_, at_, n);
  at_ += n;
  return true;
}

bool ByteReader::takeCount(uint64_t* n, size_t each) {
  return take(n) && *n <= (bytes_.size() - at_) / (each ? each : 1);
}

std::string runInChildProcess(const std::string& path, const std::string& who,
                              const std::function<std::string()>& work, bool in_process) {
  int fds[2];
  if (in_process || ::pipe(fds) != 0) return work();
  std::fflush(nullptr);  // what the parent buffered is written once, by the parent
  const pid_t pid = ::fork();
  if (pid < 0) {
    ::close(fds[0]);
    ::close(fds[1]);
    return work();
  }
  auto putAll = [](int fd, const std::string& bytes) {
    for (size_t at = 0; at < bytes.size();) {
      const ssize_t n = ::write(fd, bytes.data() + at, bytes.size() - at);
      if (n <= 0) return;
      at += static_cast<size_t>(n);
    }
  };
  if (pid == 0) {  // the child: work, send, and leave without running anything else
    ::close(fds[0]);
    // Library code never prints: whatever the library writes goes nowhere.
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) {
      ::dup2(null, 1);
      ::dup2(null, 2);
    }
    std::string out;
    try {
      out = "M" + work();
    } catch (const InputError& e) {
      out = "E" + e.field() + '\n' + e.what();
    } catch (const std::exception& e) {
      out = "E" + std::string("file\n") + e.what();
    } catch (...) {
      out = "Efile\n" + who + " failed with an unknown exception";
    }
    putAll(fds[1], out);
    ::close(fds[1]);
    ::_exit(0);
  }
  ::close(fds[1]);
  std::string in;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
    if (n > 0)
      in.append(buffer, static_cast<size_t>(n));
    else if (n == 0 || errno != EINTR)
      break;
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const bool clean = WIFEXITED(status) && WEXITSTATUS(status) == 0;
  if (clean && !in.empty() && in[0] == 'E') {
    const size_t eol = in.find('\n');
    const std::string field = in.substr(1, eol - 1);
    std::string what = in.substr(eol + 1);
    const std::string prefix = path + ": " + field + ": ";
    if (what.rfind(prefix, 0) == 0) what.erase(0, prefix.size());
    throw InputError(path, 0, 0, field, what);
  }
  if (!clean || in.empty() || in[0] != 'M') {
    std::string how =
        WIFSIGNALED(status) ? "stopped on signal " + std::to_string(WTERMSIG(status)) + " (" +
                                  strsignal(WTERMSIG(status)) + ")"
        : WIFEXITED(status) ? "stopped with exit code " + std::to_string(WEXITSTATUS(status))
                            : "stopped";
    throw InputError(path, 0, 0, "mesh", who + " " + how + " reading it: a damaged file?");
  }
  in.erase(0, 1);
  return in;
}

}  // namespace tolver
