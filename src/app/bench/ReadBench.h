// `scratchlight bench read`: seconds to read an N×N height map (default 5000²) from an
// instrument file against reading the same heights from EXR (float32, ZIP, io/ImageIO.h). The
// same synthetic heights (mm; tool-mark sine, a tilt, a few invalid points in the instrument
// files) are written as EXR, X3P (io/X3p.h writeX3p, float64 metres) and, when Gwyddion is built,
// Gwyddion's own .gwy (io/GwyddionReader.h writeGwy); each is read by loadHeightmap (reading,
// filling invalid points; no levelling) `repeats` times, median. The X3P is read twice: by our
// reader and by Gwyddion's. Gwyddion's one-time initialisation is timed apart. Files go to a
// temporary folder, removed afterwards.
#pragma once

#include <string>
#include <vector>

namespace sl {

struct ReadBenchOptions {
    int size = 5000;
    int repeats = 3;
};

struct ReadBenchRow {
    std::string format, reader;
    double megabytes = 0;   // the file's size
    double seconds = 0;     // median
    double ratioToExr = 0;  // seconds / the EXR row's
    int width = 0, height = 0;
    size_t invalidFilled = 0;
};

struct ReadBenchResult {
    ReadBenchOptions options;
    double gwyddionInitSeconds = 0;  // first call into Gwyddion (0 without it)
    std::vector<ReadBenchRow> rows;  // EXR first
    std::string csv() const;
};

/// Runs the benchmark. Throws InputError for a bad option.
ReadBenchResult runReadBench(const ReadBenchOptions& options);

}  // namespace sl
