#include "io/StagedDirectory.h"

#include <fcntl.h>
#include <stdio.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <system_error>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "io/ExitCleanup.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMarkerText =
    "written by scratchlight; the directory is replaced as a whole by the next run\n";

/// Ours: it holds the marker file with the text we write (a regular file, not a link).
bool hasMarker(const fs::path& dir) {
    std::error_code ec;
    const fs::path m = dir / StagedDirectory::kMarker;
    if (!fs::is_regular_file(fs::symlink_status(m, ec)) || fs::file_size(m, ec) > 4096)
        return false;
    std::ifstream in(m, std::ios::binary);
    const std::string text((std::istreambuf_iterator<char>(in)), {});
    return text.rfind("written by scratchlight", 0) == 0;
}

}  // namespace

StagedDirectory::StagedDirectory(fs::path target) : target_(std::move(target)) {
    const std::string where = "output directory " + target_.string();
    if (target_.empty()) throw inputError("output directory", "is empty", "give a directory");
    fs::path abs = fs::absolute(target_).lexically_normal();
    if (!abs.has_filename()) abs = abs.parent_path();  // "out/" → "out"
    std::error_code ec;
    if (fs::exists(abs, ec)) {
        if (!fs::is_directory(abs, ec))
            throw inputError(where, "is a file",
                             "give a directory (new, or one scratchlight wrote)");
        const bool empty = fs::is_empty(abs, ec) && !ec;
        if (!empty && !hasMarker(abs)) {
            // An output of a scratchlight before the marker looks like a folder of the user's
            // that holds a summary.json: neither is wiped on a guess.
            for (const char* f : {"summary.json", "judge.json"})
                if (fs::exists(abs / f, ec))
                    throw inputError(where,
                                     std::string("holds a ") + f + " but not the marker file " +
                                         kMarker +
                                         " that scratchlight writes into each output directory "
                                         "(an output of an older version, or a folder of "
                                         "yours); it is not replaced",
                                     "remove it yourself if it is an old output, or give "
                                     "another output directory");
            throw inputError(where,
                             "exists and holds files scratchlight did not write (no marker "
                             "file " +
                                 std::string(kMarker) + "); it would be replaced as a whole",
                             "give a new or empty directory, or one scratchlight wrote before");
        }
    }
    const fs::path parent = abs.parent_path();
    fs::create_directories(parent, ec);
    if (ec || !fs::is_directory(parent))
        throw inputError(where, "cannot create its parent directory " + parent.string(),
                         ec ? ec.message() : "a file is in the way");
    if (::access(parent.c_str(), W_OK | X_OK) != 0)
        throw inputError(where, "its parent directory " + parent.string() + " is not writable",
                         "choose a writable location");
    target_ = abs;
    // Built in steps: GCC 12 misreads "literal" + std::string chains under -Wrestrict (GCC bug
    // 105329).
    std::string name = ".";
    name += abs.filename().string();
    name += ".staging-";
    name += std::to_string(::getpid());
    staging_ = parent / name;
    fs::remove_all(staging_, ec);  // a leftover of a killed run with the same pid
    if (!fs::create_directory(staging_, ec) || ec)
        throw inputError(where, "cannot create the staging directory " + staging_.string(),
                         ec ? ec.message() : "");
    registerExitCleanup(staging_);  // a second Ctrl-C, which exits at once, still removes it
    std::ofstream marker(staging_ / kMarker);
    marker << kMarkerText;
    if (!marker.good()) {
        fs::remove_all(staging_, ec);
        unregisterExitCleanup(staging_);
        throw inputError(where, "cannot write in the staging directory " + staging_.string());
    }
}

StagedDirectory::~StagedDirectory() {
    if (committed_) return;
    std::error_code ec;
    fs::remove_all(staging_, ec);
    unregisterExitCleanup(staging_);
}

void StagedDirectory::commit(bool evenIfInterrupted) {
    if (committed_) throw std::logic_error("StagedDirectory::commit called twice");
    enterCommit(evenIfInterrupted);  // the last safe point: an interrupt before it keeps nothing
    std::error_code ec;
    const bool existed = fs::exists(target_, ec);
    int rc = 0;
    if (existed)
        rc = ::renameat2(AT_FDCWD, staging_.c_str(), AT_FDCWD, target_.c_str(), RENAME_EXCHANGE);
    else
        rc = ::rename(staging_.c_str(), target_.c_str());
    if (rc != 0)
        throw inputError(
            "output directory " + target_.string(),
            std::string("cannot move the new results into place: ") + std::strerror(errno),
            "the previous results are unchanged; check the file system");
    committed_ = true;
    if (existed) fs::remove_all(staging_, ec);  // the old results, now at the staging name
    unregisterExitCleanup(staging_);
}

std::string StagedDirectory::explain(const std::string& message) const {
    std::string m = message;
    const std::string from = staging_.string(), to = target_.string();
    bool staged = false;
    for (size_t p = 0; (p = m.find(from, p)) != std::string::npos; p += to.size()) {
        m.replace(p, from.size(), to);
        staged = true;
    }
    if (!staged) return m;
    for (size_t p = 0; (p = m.find("/./", p)) != std::string::npos;) m.erase(p, 2);  // "/./" → "/"
    m += " (the previous results in ";  // appended in steps: GCC 12 -Wrestrict (bug 105329)
    m += to;
    m += " are unchanged)";
    return m;
}

}  // namespace sl
