#include "app/bench/LoadBench.h"

#include <cstdio>
#include <memory>
#include <sstream>
#include <system_error>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/HeightmapIO.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

/// The baseline: the file's bytes into memory with one fread, nothing decoded. Returns the
/// bytes read (the file's size, else the read failed).
uintmax_t readRaw(const fs::path& file, std::vector<char>& buffer) {
    const std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"),
                                                            &std::fclose);
    if (!f) return 0;
    return std::fread(buffer.data(), 1, buffer.size(), f.get());
}

/// A CSV field: quoted, its quotes doubled (a reader's format and a path may hold commas).
std::string quoted(const std::string& s) {
    std::string q = "\"";
    for (char c : s) {
        if (c == '"') q += '"';
        q += c;
    }
    return q + '"';
}

}  // namespace

LoadBenchResult runLoadBench(const LoadBenchOptions& o) {
    if (o.files.empty())
        throw inputError("files", "none given", "name one or more height-map files");
    if (o.repeats < 1) throw inputError("repeats", "is " + std::to_string(o.repeats), "use >= 1");
    LoadBenchResult result;
    result.options = o;
    // A bare height map as loadHeightSource reads it (io/SceneFile.cpp): an integer map without
    // a height range as [0, 1], levelled by auto at the file's pitch (1 without one).
    HeightmapOptions readOptions;
    readOptions.defaultIntegerRange = std::array<double, 2>{0.0, 1.0};
    {
        ProgressTask task("bench load: the first read of each file",
                          static_cast<double>(o.files.size()));
        for (const fs::path& file : o.files) {
            throwIfInterrupted();
            LoadBenchRow row;
            row.file = file;
            const Stopwatch first;
            const HeightmapData d = loadHeightmap(file, readOptions);
            row.firstSeconds = first.seconds();
            std::error_code ec;
            row.bytes = fs::file_size(file, ec);
            if (ec) throw inputError(file.string(), "cannot read its size: " + ec.message());
            row.reader = d.format;
            row.width = d.width;
            row.height = d.height;
            row.invalidFilled = d.invalidFilled;
            row.resampling = d.resampling;
            result.rows.push_back(row);
            task.advance();
        }
    }
    const size_t n = o.files.size();
    std::vector<std::vector<double>> raw(n), read(n), readCpu(n), level(n);
    ProgressTask task("bench load", static_cast<double>(n) * o.repeats);
    for (int r = 0; r < o.repeats; ++r) {
        for (size_t i = 0; i < n; ++i) {
            throwIfInterrupted();
            LoadBenchRow& row = result.rows[i];
            std::vector<char> buffer(static_cast<size_t>(row.bytes));
            const Stopwatch rawClock;
            const uintmax_t got = readRaw(row.file, buffer);
            raw[i].push_back(rawClock.seconds());
            if (got != row.bytes)
                throw inputError(row.file.string(),
                                 "read " + std::to_string(got) + " of its " +
                                     std::to_string(row.bytes) + " bytes",
                                 "check that the file is not changing during the benchmark");
            buffer = {};
            const Stopwatch readClock;
            const CpuStopwatch readCpuClock;
            HeightmapData d = loadHeightmap(row.file, readOptions);
            readCpu[i].push_back(readCpuClock.seconds());
            read[i].push_back(readClock.seconds());
            const Stopwatch levelClock;
            row.levelling =
                levelHeights(d.heights, d.width, d.height, d.pitch.value_or(1.0), d.invalid,
                             LevellingDesc{}, d.measured(), row.file.string());
            level[i].push_back(levelClock.seconds());
            task.advance();
        }
    }
    for (size_t i = 0; i < n; ++i) {
        LoadBenchRow& row = result.rows[i];
        row.rawSeconds = median(raw[i]);
        row.readSeconds = median(read[i]);
        row.readCpuSeconds = median(readCpu[i]);
        row.levelSeconds = median(level[i]);
    }
    return result;
}

std::string LoadBenchResult::csv() const {
    std::ostringstream os;
    os << "file,reader,bytes,width,height,invalid_filled,resampled,levelling,repeats,"
          "first_seconds,raw_seconds,raw_mb_per_s,read_seconds,read_cpu_seconds,read_mb_per_s,"
          "read_msamples_per_s,read_to_raw,level_seconds\n";
    for (const LoadBenchRow& r : rows)
        os << quoted(r.file.string()) << ',' << quoted(r.reader) << ',' << r.bytes << ',' << r.width
           << ',' << r.height << ',' << r.invalidFilled << ',' << (r.resampling.empty() ? 0 : 1)
           << ',' << quoted(levellingName(r.levelling.applied)) << ',' << options.repeats << ','
           << r.firstSeconds << ',' << r.rawSeconds << ',' << r.rawMBps() << ',' << r.readSeconds
           << ',' << r.readCpuSeconds << ',' << r.readMBps() << ','
           << r.samples() / r.readSeconds / 1e6 << ',' << r.readRatio() << ',' << r.levelSeconds
           << '\n';
    return os.str();
}

}  // namespace sl
