// AtomicOutput: write a file under a temporary name in the destination directory and rename it
// into place only when the write has fully succeeded (docs/DESIGN.md "Files": every output is
// written under a temporary name and renamed into place).
//
//   AtomicOutput out(finalPath);          // creates missing parent directories
//   writeSomething(out.tempPath());       // may throw: ~AtomicOutput removes the temporary
//   out.commit();                         // fsync + rename(temp, final): final appears whole
//
// Guarantees: a file that already exists at `finalPath` is replaced only by commit(), never
// truncated or removed by a failed write; a failed or abandoned write leaves no temporary file
// and removes the (empty) directories that this object created. The temporary name is
// `.<stem>.tmp-<pid>-<counter><extension>` in the same directory, so the rename never crosses a
// file system and libraries that infer the format from the extension (OpenImageIO) still do.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <string_view>
#include <vector>

namespace sl {

class AtomicOutput {
  public:
    /// Prepares a temporary path beside `finalPath`; creates missing parent directories.
    /// Throws InputError (naming the file) when the directory cannot be created or
    /// `finalPath` names a directory.
    explicit AtomicOutput(std::filesystem::path finalPath);
    ~AtomicOutput();
    AtomicOutput(const AtomicOutput&) = delete;
    AtomicOutput& operator=(const AtomicOutput&) = delete;

    const std::filesystem::path& finalPath() const { return final_; }
    const std::filesystem::path& tempPath() const { return temp_; }
    bool committed() const { return committed_; }

    /// Flushes the temporary file to disk and renames it onto finalPath (atomic on POSIX).
    /// Throws InputError if the temporary file is missing or the rename fails; the temporary
    /// is removed then too. Calling commit() twice is an error.
    void commit();

    /// Abandons the write now (what the destructor does): removes the temporary file and the
    /// empty directories created by the constructor. Never throws.
    void abandon() noexcept;

  private:
    std::filesystem::path final_, temp_;
    std::vector<std::filesystem::path> createdDirs_;  // deepest last
    bool committed_ = false;
    bool abandoned_ = false;
};

/// Convenience: AtomicOutput out(file); write(out.tempPath()); out.commit().
void writeAtomically(const std::filesystem::path& file,
                     const std::function<void(const std::filesystem::path& temp)>& write);

/// Writes `text` (CSV, JSON, HTML, ...) to `file` atomically; a failed write (stream error,
/// disk full) throws InputError naming the file and leaves nothing behind.
void writeTextAtomically(const std::filesystem::path& file, std::string_view text);

/// The same for bytes (an image encoded in memory, ...).
void writeBytesAtomically(const std::filesystem::path& file, const void* data, size_t size);

/// Writes `size` bytes to `path` (a temporary) and closes it, checking every step; throws
/// InputError naming `file` (what the user asked for) when a write, the flush or the close
/// fails (disk full, file-size limit, I/O error).
void writeBytesChecked(const std::filesystem::path& path, const void* data, size_t size,
                       const std::filesystem::path& file);

}  // namespace sl
