#include "util/atomic_file.h"

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include "util/error.h"

namespace vkray {

namespace fs = std::filesystem;

namespace {

// A write to NAME goes through ".NAME.tmp-PID-XXXXXX" in the same directory. A process killed
// between creating and renaming it (SIGKILL, power loss) leaves that hidden file behind; the next
// write to NAME removes those whose PID no longer runs. A live writer's file is never touched.
std::string temporaryPrefix(const fs::path& path) {
  // Appended piece by piece: GCC 12 warns (-Wstringop-overflow, a false positive) on "." + string.
  std::string prefix = ".";
  prefix += path.filename().string();
  prefix += ".tmp-";
  return prefix;
}

void removeStaleTemporaries(const fs::path& dir, const fs::path& path) {
  const std::string prefix = temporaryPrefix(path);
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    std::string name = it->path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const char* digits = name.c_str() + prefix.size();
    char* rest = nullptr;
    long pid = std::strtol(digits, &rest, 10);
    if (rest == digits || *rest != '-' || pid <= 0) continue;
    // ESRCH: no such process. EPERM means it runs under another user: keep its file.
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    ::unlink(it->path().c_str());
  }
}

// The write itself: nullptr when done, else what failed (errno says why); the temporary is gone
// either way.
const char* writeThroughTemporary(const fs::path& path, std::span<const std::uint8_t> bytes, bool durable) {
  fs::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  removeStaleTemporaries(dir, path);
  std::string tmpl = (dir / (temporaryPrefix(path) + std::to_string(::getpid()) + "-XXXXXX")).string();
  std::vector<char> name(tmpl.begin(), tmpl.end());
  name.push_back('\0');
  int fd = ::mkstemp(name.data());
  if (fd < 0) return "cannot create a file here";
  auto fail = [&](const char* what) {
    int err = errno;
    if (fd >= 0) ::close(fd);
    ::unlink(name.data());
    errno = err;
    return what;
  };
  std::size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail("cannot write");
    }
    done += static_cast<std::size_t>(n);
  }
  if (durable && ::fsync(fd) != 0) return fail("cannot flush to disk");
  ::fchmod(fd, 0644);
  const int closed = ::close(fd);
  fd = -1;
  if (closed != 0) return fail("cannot close");
  if (::rename(name.data(), path.c_str()) != 0) return fail("cannot replace");
  return nullptr;
}

} // namespace

void writeFileAtomic(const fs::path& path, std::span<const std::uint8_t> bytes) {
  if (const char* failed = writeThroughTemporary(path, bytes, true)) {
    throw InputError(path.string(), std::string(failed) + ": " + std::strerror(errno));
  }
}

bool writeFileAtomicQuietly(const fs::path& path, std::span<const std::uint8_t> bytes) noexcept {
  try {
    return writeThroughTemporary(path, bytes, false) == nullptr;
  } catch (...) { // std::bad_alloc, or a path that cannot be converted
    return false;
  }
}

} // namespace vkray
