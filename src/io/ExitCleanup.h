// What a second Ctrl-C (or SIGTERM), which ends the process at once (core/Interrupt.h), must
// still undo: the staging directories and temporary files of outputs being written
// (io/StagedDirectory.h, io/AtomicFile.h) are removed, and the process groups of external
// programs we started (app/host/ExternalRenderer.h) are killed, so nothing of ours outlives the
// process. Registration is cheap and thread-safe; exitAtOnce() is async-signal-safe (raw system
// calls only: openat, getdents64, unlinkat, kill, _exit) and is what the command line's signal
// handler calls on the second signal.
#pragma once

#include <sys/types.h>

#include <filesystem>

namespace sl {

/// A path (file or directory tree) to remove if the process exits at once; at most 32 at a
/// time (more are not registered: a leftover then stays, as before). Paths longer than 4095
/// bytes are not registered either.
void registerExitCleanup(const std::filesystem::path& path) noexcept;
void unregisterExitCleanup(const std::filesystem::path& path) noexcept;

/// A process group (a child started with its own group) to kill (SIGKILL) on exit at once.
void registerExitProcessGroup(pid_t group) noexcept;
void unregisterExitProcessGroup(pid_t group) noexcept;

/// Kills the registered process groups, removes the registered paths, then _exit(code).
/// Async-signal-safe.
[[noreturn]] void exitAtOnce(int code) noexcept;

/// Removes `path` (a file, or a directory tree, symlinks not followed) with raw system calls
/// only: async-signal-safe. Returns false when something could not be removed.
bool removeTreeSignalSafe(const char* path) noexcept;

}  // namespace sl
