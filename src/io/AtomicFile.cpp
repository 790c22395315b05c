#include "io/AtomicFile.h"

#include <atomic>
#include <cerrno>
#include <fstream>
#include <string>
#include <system_error>

#include "core/Error.h"
#include "io/ExitCleanup.h"

#if defined(__unix__) || defined(__APPLE__)
#include <fcntl.h>
#include <unistd.h>
#define SL_HAVE_POSIX 1
#endif

namespace sl {

namespace fs = std::filesystem;

namespace {

std::atomic<unsigned long long> gTempCounter{0};

long processId() {
#ifdef SL_HAVE_POSIX
    return static_cast<long>(::getpid());
#else
    return 0;
#endif
}

/// Pushes the file's data to disk before the rename makes it visible. Returns false when the
/// file system reports that data was lost (EIO, ENOSPC, EDQUOT: delayed allocation fails only
/// now on some file systems); other failures (fsync unsupported) count as success.
bool syncFile(const fs::path& p) {
#ifdef SL_HAVE_POSIX
    int fd = ::open(p.c_str(), O_RDONLY);
    if (fd < 0) return true;
    const bool lost = ::fsync(fd) != 0 && (errno == EIO || errno == ENOSPC || errno == EDQUOT);
    (void)::close(fd);
    return !lost;
#else
    (void)p;
    return true;
#endif
}

}  // namespace

AtomicOutput::AtomicOutput(fs::path finalPath) : final_(std::move(finalPath)) {
    const std::string where = final_.string();
    if (final_.empty()) throw inputError("output file", "empty file name", "Give a file name");
    if (!final_.has_filename() || final_.filename() == "." || final_.filename() == "..")
        throw inputError(where, "not a file name", "Give a file name, not a directory");

    std::error_code ec;
    if (fs::is_directory(final_, ec))
        throw inputError(where, "is a directory",
                         "Give a file name, or remove the directory of that name");

    // Create missing parent directories, remembering which ones so a failed write can remove
    // them again (only if still empty).
    fs::path parent = final_.parent_path();
    if (!parent.empty()) {
        std::vector<fs::path> missing;
        for (fs::path p = parent; !p.empty(); p = p.parent_path()) {
            if (fs::exists(p, ec)) break;
            missing.push_back(p);
            if (p == p.parent_path()) break;
        }
        for (auto it = missing.rbegin(); it != missing.rend(); ++it) {
            if (!fs::create_directory(*it, ec) || ec) {
                abandon();
                throw inputError(where,
                                 "cannot create the directory " + it->string() +
                                     (ec ? " (" + ec.message() + ")" : ""),
                                 "Check that the path is writable and its parents are "
                                 "directories");
            }
            createdDirs_.push_back(*it);
        }
        if (!fs::is_directory(parent, ec)) {
            abandon();
            throw inputError(where, "the parent " + parent.string() + " is not a directory",
                             "Choose an output path inside a directory");
        }
    }

    std::string name(".");
    name += final_.stem().string();
    name += ".tmp-";
    name += std::to_string(processId());
    name += '-';
    name += std::to_string(gTempCounter.fetch_add(1));
    name += final_.extension().string();
    temp_ = final_.parent_path() / name;
    registerExitCleanup(temp_);  // a second Ctrl-C, which exits at once, still removes it
}

AtomicOutput::~AtomicOutput() {
    if (!committed_) abandon();
}

void AtomicOutput::abandon() noexcept {
    if (abandoned_ || committed_) return;
    abandoned_ = true;
    std::error_code ec;
    if (!temp_.empty()) fs::remove(temp_, ec);
    unregisterExitCleanup(temp_);
    // Deepest first; fs::remove on a directory only succeeds when it is empty.
    for (auto it = createdDirs_.rbegin(); it != createdDirs_.rend(); ++it) fs::remove(*it, ec);
    createdDirs_.clear();
}

void AtomicOutput::commit() {
    const std::string where = final_.string();
    if (committed_ || abandoned_)
        throw inputError(where, "internal error: AtomicOutput committed twice or after abandon");
    std::error_code ec;
    if (!fs::is_regular_file(temp_, ec)) {
        abandon();
        throw inputError(where, "the writer produced no file (expected " + temp_.string() + ")",
                         "Check free disk space and permissions");
    }
    if (!syncFile(temp_)) {
        abandon();
        throw inputError(where, "the file system lost the written data (disk full or I/O error)",
                         "Check free disk space and try again");
    }
    fs::rename(temp_, final_, ec);
    if (ec) {
        abandon();
        throw inputError(where, "cannot move the finished file into place (" + ec.message() + ")",
                         "Check permissions of the directory and that the name is not a "
                         "directory");
    }
    committed_ = true;
    unregisterExitCleanup(temp_);
    createdDirs_.clear();
}

void writeAtomically(const fs::path& file, const std::function<void(const fs::path&)>& write) {
    AtomicOutput out(file);
    write(out.tempPath());
    out.commit();
}

void writeBytesChecked(const fs::path& path, const void* data, size_t size, const fs::path& file) {
    std::ofstream os(path, std::ios::binary | std::ios::trunc);
    os.write(static_cast<const char*>(data), static_cast<std::streamsize>(size));
    os.close();  // flushes; a failed flush or close sets failbit
    if (!os)
        throw inputError(file.string(), "cannot be written (disk full or not writable?)",
                         "check that the directory is writable and the disk has space");
}

void writeTextAtomically(const fs::path& file, std::string_view text) {
    writeBytesAtomically(file, text.data(), text.size());
}

void writeBytesAtomically(const fs::path& file, const void* data, size_t size) {
    writeAtomically(file, [&](const fs::path& tmp) { writeBytesChecked(tmp, data, size, file); });
}

}  // namespace sl
