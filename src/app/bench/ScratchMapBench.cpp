#include "app/bench/ScratchMapBench.h"

#include <cmath>
#include <sstream>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"

namespace sl {

std::vector<float> scratchMapBenchHeights(int n) {
    if (n < 1) throw inputError("sizes", "contains " + std::to_string(n), "use sizes >= 1");
    const auto N = static_cast<size_t>(n);
    std::vector<float> h(N * N);
    for (size_t y = 0; y < N; ++y)
        for (size_t x = 0; x < N; ++x)
            h[y * N + x] =
                0.01f * std::sin(0.157f * static_cast<float>(x)) + 1e-5f * static_cast<float>(y);
    h[(N / 2) * N + N / 2] -= 0.05f;  // one "scratch"
    return h;
}

ScratchMapBenchResult runScratchMapBench(const ScratchMapBenchOptions& o) {
    if (o.repeats < 1) throw inputError("repeats", "is " + std::to_string(o.repeats), "use >= 1");
    ScratchMapBenchResult result;
    result.options = o;
    ProgressTask task("bench scratchmap", static_cast<double>(o.sizes.size()) * o.repeats);
    for (int n : o.sizes) {
        const std::vector<float> h = scratchMapBenchHeights(n);
        ScratchMapBenchRow row;
        row.size = n;
        std::vector<double> seconds;
        for (int r = 0; r < o.repeats; ++r) {
            throwIfInterrupted();
            const ScratchMap m = computeScratchMap(h, n, n, o.map);
            seconds.push_back(m.seconds);
            task.advance();
            row.patches = m.patchesX * m.patchesY;
            row.patchesMarked = m.patchesMarked;
            row.markedFraction = m.markedFraction();
        }
        row.seconds = median(seconds);
        result.rows.push_back(row);
    }
    return result;
}

std::string ScratchMapBenchResult::csv() const {
    std::ostringstream os;
    os << "size,kernel,patch,threshold,repeats,seconds,patches,patches_marked,marked_fraction\n";
    for (const ScratchMapBenchRow& r : rows)
        os << r.size << ',' << options.map.kernel << ',' << options.map.patch << ','
           << options.map.threshold << ',' << options.repeats << ',' << r.seconds << ','
           << r.patches << ',' << r.patchesMarked << ',' << r.markedFraction << '\n';
    return os.str();
}

}  // namespace sl
