#include "app/bench/ReadBench.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/Error.h"
#include "core/Image.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "core/Stopwatch.h"
#include "io/GwyddionReader.h"
#include "io/HeightmapIO.h"
#include "io/ImageIO.h"
#include "io/NanoFocusNms.h"
#include "io/TrueMap.h"
#include "io/X3p.h"

namespace sl {

namespace fs = std::filesystem;

namespace {

struct TempFolder {
    fs::path path;
    TempFolder() {
        std::string t = (fs::temp_directory_path() / "scratchlight-bench-read-XXXXXX").string();
        if (!mkdtemp(t.data()))
            throw inputError(fs::temp_directory_path().string(), "cannot create a temporary folder",
                             "check TMPDIR");
        path = t;
    }
    ~TempFolder() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
};

}  // namespace

ReadBenchResult runReadBench(const ReadBenchOptions& o) {
    if (o.size < 2 || o.size > 20000)
        throw inputError("size", "is " + std::to_string(o.size), "use 2..20000");
    if (o.repeats < 1) throw inputError("repeats", "is " + std::to_string(o.repeats), "use >= 1");
    ReadBenchResult result;
    result.options = o;
    const int n = o.size;
    const auto N = static_cast<size_t>(n);
    const double pitch = 0.002;  // mm
    std::vector<float> h(N * N);
    for (size_t y = 0; y < N; ++y)
        for (size_t x = 0; x < N; ++x)
            h[y * N + x] =
                0.001f * std::sin(0.157f * static_cast<float>(x)) + 2e-6f * static_cast<float>(y);
    TempFolder dir;
    const fs::path exr = dir.path / "heights.exr", x3p = dir.path / "heights.x3p",
                   gwy = dir.path / "heights.gwy", tmd = dir.path / "heights.tmd",
                   nms = dir.path / "heights.nms";
    {
        ProgressTask task("bench read: writing the files");
        Image img(n, n, 1);
        img.data = h;
        writeExr(exr, img);
        throwIfInterrupted();  // between the files: the temporary folder goes with the throw
        // the instrument files carry invalid points (NaN), as real measurements do
        std::vector<float> withNan = h;
        for (size_t k = 0; k < withNan.size(); k += 9973)
            withNan[k] = std::numeric_limits<float>::quiet_NaN();
        writeX3p(x3p, n, n, withNan, pitch);
        throwIfInterrupted();
        writeTrueMap(tmd, n, n, withNan, pitch);
        throwIfInterrupted();
        writeNanoFocusNms(nms, n, n, h, pitch);  // (no invalid-point code in this format)
        throwIfInterrupted();
        if (gwyddionBuilt()) {
            const Stopwatch init;
            (void)gwyddionDetect(exr);
            result.gwyddionInitSeconds = init.seconds();
            writeGwy(gwy, n, n, withNan, pitch);
        }
    }
    struct Case {
        std::string format, reader;
        fs::path file;
        HeightmapReader how;
    };
    std::vector<Case> cases = {
        {"exr float32", "OpenEXR (io/ExrReader.cpp)", exr, HeightmapReader::Auto},
        {"x3p float64", "ours (io/X3p.cpp)", x3p, HeightmapReader::Auto},
        {"tmd float32", "ours (io/TrueMap.cpp)", tmd, HeightmapReader::Auto},
        {"nms uint16", "ours (io/NanoFocusNms.cpp)", nms, HeightmapReader::Auto}};
    if (gwyddionBuilt()) {
        cases.push_back({"x3p float64", "Gwyddion (opengps)", x3p, HeightmapReader::Gwyddion});
        cases.push_back({"gwy float64", "Gwyddion (gwyfile)", gwy, HeightmapReader::Auto});
    }
    ProgressTask task("bench read", static_cast<double>(cases.size()) * o.repeats);
    for (const Case& c : cases) {
        ReadBenchRow row;
        row.format = c.format;
        row.reader = c.reader;
        row.megabytes = static_cast<double>(fs::file_size(c.file)) / 1e6;
        std::vector<double> seconds;
        for (int r = 0; r < o.repeats; ++r) {
            throwIfInterrupted();
            const Stopwatch clock;
            const HeightmapData d = loadHeightmap(c.file, {}, c.how);
            seconds.push_back(clock.seconds());
            row.width = d.width;
            row.height = d.height;
            row.invalidFilled = d.invalidFilled;
            task.advance();
        }
        row.seconds = median(seconds);
        result.rows.push_back(row);
    }
    for (ReadBenchRow& r : result.rows) r.ratioToExr = r.seconds / result.rows.front().seconds;
    return result;
}

std::string ReadBenchResult::csv() const {
    std::ostringstream os;
    os << "format,reader,width,height,megabytes,repeats,seconds,ratio_to_exr,invalid_filled,"
          "gwyddion_init_seconds\n";
    for (const ReadBenchRow& r : rows)
        os << r.format << ',' << r.reader << ',' << r.width << ',' << r.height << ',' << r.megabytes
           << ',' << options.repeats << ',' << r.seconds << ',' << r.ratioToExr << ','
           << r.invalidFilled << ',' << gwyddionInitSeconds << '\n';
    return os.str();
}

}  // namespace sl
