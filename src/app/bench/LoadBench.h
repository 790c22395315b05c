// `scratchlight bench load FILE...`: where loading a real part's height map goes, file by file,
// against a raw read of the same bytes in the same run. Each file is loaded as every command
// loads a bare height map (io/SceneFile.h loadHeightSource): its reader (io/HeightmapIO.h
// loadHeightmap: the file decoded, invalid points filled, non-square pixels resampled), then
// the default levelling (scene/Levelling.h levelHeights, auto: a plane on a measured map), each
// timed apart; the baseline is the file's bytes read into memory with one fread (the page
// cache warm for both). Per repeat the files are taken in turn and, per file, the raw read, the
// reader and the levelling one after the other (interleaved, so a change of the machine's load
// shifts all three); medians over repeats. The reader's first call on the first file (timed
// apart, before the repeats) includes loading its module the first time the process needs it
// (Gwyddion's, OpenImageIO's: DESIGN "Build"). Wall seconds, and the reader's CPU seconds
// (the process's, std::clock), which a loaded machine disturbs less.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "scene/Levelling.h"

namespace sl {

struct LoadBenchOptions {
    std::vector<std::filesystem::path> files;  // height maps (no scene files)
    int repeats = 5;
};

struct LoadBenchRow {
    std::filesystem::path file;
    std::string reader;  // HeightmapData::format, e.g. "gwyddion opdfile"
    uintmax_t bytes = 0;
    int width = 0, height = 0;  // after resampling
    size_t invalidFilled = 0;
    std::string resampling;  // "" or what was done
    LevellingResult levelling;
    double firstSeconds = 0;    // the first loadHeightmap of this file (wall)
    double rawSeconds = 0;      // median: the file's bytes into memory
    double readSeconds = 0;     // median: loadHeightmap
    double readCpuSeconds = 0;  // median: loadHeightmap, the process's CPU seconds
    double levelSeconds = 0;    // median: levelHeights on the loaded map
    double rawMBps() const { return megabytes() / rawSeconds; }
    double readMBps() const { return megabytes() / readSeconds; }
    double megabytes() const { return static_cast<double>(bytes) / 1e6; }
    double samples() const { return static_cast<double>(width) * height; }
    double readRatio() const { return readSeconds / rawSeconds; }  // the reader over raw bytes
};

struct LoadBenchResult {
    LoadBenchOptions options;
    std::vector<LoadBenchRow> rows;  // in the files' order
    std::string csv() const;         // header + one line per file
};

/// Runs the benchmark. Throws InputError for no file, a bad option or a file no reader reads
/// (the reader's own error, naming the file).
LoadBenchResult runLoadBench(const LoadBenchOptions& options);

}  // namespace sl
