// StagedDirectory: an output directory replaced as a unit. Everything is written into a sibling
// staging directory; commit() swaps it with the old one in one step (Linux renameat2
// RENAME_EXCHANGE, or a plain rename when there was none) and then removes the old results. A
// failure or interruption before commit() removes the staging directory and leaves the previous
// results exactly as they were: never a mix of old and new, never a stray temporary.
//
//   StagedDirectory out(outDir);   // checks the location first, before any work
//   write(out.path() / "a.exr");   // ... every file of the run
//   out.commit();                  // outDir now holds exactly the new files
//
// Ctrl-C (core/Interrupt.h): commit() is the command's last safe point (enterCommit): an
// interrupt before it throws Interrupted and leaves the previous results; one after it lets the
// swap finish. A second signal, which exits at once, still removes the staging directory
// (io/ExitCleanup.h).
//
// Safety: a directory is replaced only if it is empty or one this class wrote before (it holds
// the marker file `.scratchlight-output` with the text this class writes). Anything else (e.g.
// `-o .` or a folder of the user's) is refused before the work starts, so no command can wipe
// files it did not write. A folder with a summary.json or judge.json but no marker (an output of
// a scratchlight before the marker, or a folder of the user's that happens to hold such a file)
// is refused too, with a message saying so and how to proceed.
#pragma once

#include <filesystem>
#include <string>

namespace sl {

class StagedDirectory {
  public:
    /// The marker file each committed directory holds.
    static constexpr const char* kMarker = ".scratchlight-output";

    /// Checks that `target` can be (re)placed: not a file, not a directory of someone else's,
    /// its parent creatable and writable; creates the staging directory
    /// `<parent>/.<name>.staging-<pid>`. Throws InputError naming `target` and the fix.
    explicit StagedDirectory(std::filesystem::path target);
    ~StagedDirectory();  // removes the staging directory unless committed
    StagedDirectory(const StagedDirectory&) = delete;
    StagedDirectory& operator=(const StagedDirectory&) = delete;

    const std::filesystem::path& path() const { return staging_; }  // write here
    const std::filesystem::path& target() const { return target_; }

    /// Swaps the staged directory into place and removes the old results. Throws Interrupted
    /// when an interrupt was requested (unless `evenIfInterrupted`: results the user asked to
    /// keep, core/Interrupt.h enterCommit), InputError naming the target when the swap fails;
    /// the old results then stay in place.
    void commit(bool evenIfInterrupted = false);

    /// A message about a file in the staging directory, said about the target instead (the
    /// staging directory is gone by the time the user reads it), noting that the previous
    /// results are unchanged; other messages as they are.
    std::string explain(const std::string& message) const;

  private:
    std::filesystem::path target_, staging_;
    bool committed_ = false;
};

}  // namespace sl
