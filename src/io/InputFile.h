// Reading an input file the user named, and the JSON in it, with bounds: a path must be a
// regular file of plausible size before it is opened (a FIFO would block the open, a device such
// as /dev/zero would be read without end), JSON is refused past a nesting depth and a size before
// it is parsed, and a JSON value quoted in a message is a bounded prefix of its text (the JSON
// library's dump() recurses once per level and would overflow the stack on a value nested
// tens of thousands deep).
#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace sl {

/// Largest JSON input file read (scene files, lamps.json, legends, summaries, report specs).
inline constexpr uint64_t kMaxJsonFileBytes = 16ull << 20;
/// Deepest nesting of arrays and objects admitted in any JSON we read (ours is at most ~6).
inline constexpr int kMaxJsonDepth = 64;
/// Longest quote of an input value in a message, in characters.
inline constexpr size_t kMaxQuoteChars = 80;

/// Throws InputError naming `file` (as "<file>: <problem>. <fix>") unless it exists, is a
/// regular file (after symlinks: not a directory, FIFO, socket or device) and holds at most
/// `maxBytes` bytes. `what` names the kind of file ("the scene file"). Never opens the file.
void checkInputFile(const std::filesystem::path& file, const std::string& what, uint64_t maxBytes,
                    const std::string& fix = {});

/// checkInputFile, then the whole file's bytes (at most `maxBytes`: a file that grew since is
/// refused too).
std::string readInputFile(const std::filesystem::path& file, const std::string& what,
                          uint64_t maxBytes, const std::string& fix = {});

/// Parses JSON text after checking its size (kMaxJsonFileBytes) and nesting depth
/// (kMaxJsonDepth) without recursion. InputError "<where>: not valid JSON: ..." or "nested
/// deeper than 64 levels" otherwise, with `fix` appended.
nlohmann::json parseJsonInput(std::string_view text, const std::string& where,
                              const std::string& fix = {});

/// readInputFile (kMaxJsonFileBytes) and parseJsonInput.
nlohmann::json readJsonInput(const std::filesystem::path& file, const std::string& what,
                             const std::string& fix = {});

/// The deepest nesting of arrays/objects in JSON text (strings skipped), counted without
/// parsing or recursion; stops counting once past `limit` (returns limit + 1).
int jsonNestingDepth(std::string_view text, int limit = kMaxJsonDepth);

/// A JSON value's text for a message: at most `maxChars` characters, "..." when cut. Bounded in
/// time, stack and output whatever the value's size or depth.
std::string jsonExcerpt(const nlohmann::json& v, size_t maxChars = kMaxQuoteChars);

/// Plain text for a message: at most `maxChars` characters, control and non-ASCII bytes as
/// \xNN, "..." when cut (a binary file's bytes quoted as a "file name").
std::string textExcerpt(std::string_view s, size_t maxChars = kMaxQuoteChars);

/// Whether `a` and `b` name the same file: the same inode when both exist (hard links, symlinks,
/// "./x" and "x"), else the same weakly canonical path.
bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b);

/// Whether `file` is `dir` or lies anywhere under it (paths resolved through symlinks).
bool insideDirectory(const std::filesystem::path& file, const std::filesystem::path& dir);

/// An output never replaces an input of the same run: throws InputError naming `output` (what it
/// is: `what`) and the input when `output` is the same file as one of `inputs` (empty paths and
/// names of no file, such as a preset's, are skipped) or, when `directory` (an output folder
/// replaced as a whole), holds one of them.
void refuseOutputOverInput(const std::filesystem::path& output, const std::string& what,
                           const std::vector<std::filesystem::path>& inputs,
                           bool directory = false);

}  // namespace sl
