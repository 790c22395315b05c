#include "io/ExitCleanup.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>

namespace sl {

namespace {

constexpr int kSlots = 32;
constexpr size_t kMaxPath = 4096;

// A slot is free (0), being written (1) or holds a path (2). Only a slot in state 2 is read by
// exitAtOnce, so a path is never read half-written.
struct PathSlot {
    std::atomic<int> state{0};
    char path[kMaxPath]{};
};
PathSlot gPaths[kSlots];
std::atomic<pid_t> gGroups[kSlots];

static_assert(std::atomic<int>::is_always_lock_free && std::atomic<pid_t>::is_always_lock_free);

/// Removes `name` under `dirfd` (a file, or a directory and everything in it), `depth` levels
/// at most. Raw system calls only.
bool removeAt(int dirfd, const char* name, int depth) noexcept {
    if (::unlinkat(dirfd, name, 0) == 0 || errno == ENOENT) return true;
    if (errno != EISDIR && errno != EPERM) return false;
    if (depth <= 0) return false;
    const int fd = ::openat(dirfd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
    if (fd < 0) return false;
    bool ok = true;
    // Entries are removed while the directory is read: read it again from the start until a
    // pass finds nothing left to remove (or removes nothing more).
    for (int pass = 0; pass < 64; ++pass) {
        alignas(8) char buf[2048];
        bool removedAny = false, sawAny = false;
        ::lseek(fd, 0, SEEK_SET);
        for (;;) {
            const long n = ::syscall(SYS_getdents64, fd, buf, sizeof buf);
            if (n <= 0) break;
            for (long off = 0; off < n;) {
                const auto* d = reinterpret_cast<const struct dirent64*>(buf + off);
                off += d->d_reclen;
                const char* e = d->d_name;
                if ((e[0] == '.' && e[1] == 0) || (e[0] == '.' && e[1] == '.' && e[2] == 0))
                    continue;
                sawAny = true;
                if (removeAt(fd, e, depth - 1)) removedAny = true;
            }
        }
        if (!sawAny || !removedAny) break;
    }
    ::close(fd);
    if (::unlinkat(dirfd, name, AT_REMOVEDIR) != 0 && errno != ENOENT) ok = false;
    return ok;
}

bool samePath(const char* a, const char* b) noexcept {
    return std::strcmp(a, b) == 0;
}

}  // namespace

bool removeTreeSignalSafe(const char* path) noexcept {
    const int saved = errno;
    const bool ok = removeAt(AT_FDCWD, path, 16);
    errno = saved;
    return ok;
}

void registerExitCleanup(const std::filesystem::path& path) noexcept {
    const std::string& s = path.native();
    if (s.empty() || s.size() >= kMaxPath) return;
    for (PathSlot& slot : gPaths) {
        int expected = 0;
        if (!slot.state.compare_exchange_strong(expected, 1)) continue;
        std::memcpy(slot.path, s.c_str(), s.size() + 1);
        slot.state.store(2);
        return;
    }
}

void unregisterExitCleanup(const std::filesystem::path& path) noexcept {
    for (PathSlot& slot : gPaths) {
        int expected = 2;
        if (slot.state.load() != 2 || !samePath(slot.path, path.c_str())) continue;
        if (slot.state.compare_exchange_strong(expected, 0)) return;
    }
}

void registerExitProcessGroup(pid_t group) noexcept {
    if (group <= 0) return;
    for (std::atomic<pid_t>& g : gGroups) {
        pid_t expected = 0;
        if (g.compare_exchange_strong(expected, group)) return;
    }
}

void unregisterExitProcessGroup(pid_t group) noexcept {
    for (std::atomic<pid_t>& g : gGroups) {
        pid_t expected = group;
        if (g.compare_exchange_strong(expected, 0)) return;
    }
}

void exitAtOnce(int code) noexcept {
    for (std::atomic<pid_t>& g : gGroups)
        if (const pid_t group = g.load(); group > 0) ::kill(-group, SIGKILL);
    for (PathSlot& slot : gPaths)
        if (slot.state.load() == 2) removeTreeSignalSafe(slot.path);
    ::_exit(code);
}

}  // namespace sl
