#include "app/bench/DefectMapBench.h"

#include <sstream>

#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Progress.h"
#include "core/Stats.h"
#include "synth/SurfaceGenerator.h"

namespace sl {

DefectMapBenchResult runDefectMapBench(const DefectMapBenchOptions& o) {
    if (o.repeats < 1) throw inputError("repeats", "is " + std::to_string(o.repeats), "use >= 1");
    for (int n : o.sizes)
        if (n < 2) throw inputError("sizes", "contains " + std::to_string(n), "use sizes >= 2");
    DefectMapBenchResult result;
    result.options = o;
    DefectMapOptions autoOptions = o.map;
    autoOptions.method = DefectMethod::Auto;
    DefectMapOptions paperOptions = o.map;
    paperOptions.method = DefectMethod::Paper;
    ProgressTask task("bench defectmap", static_cast<double>(o.sizes.size()) * o.repeats);
    for (int n : o.sizes) {
        SurfaceSpec spec = testPartSpec(TestPart::BallEnd);
        spec.width = spec.height = n;
        const GeneratedSurface part = generateSurface(spec);
        DefectMapBenchRow row;
        row.size = n;
        std::vector<double> tAuto, tPaper;
        for (int r = 0; r < o.repeats; ++r) {
            throwIfInterrupted();
            const DefectMap a = detectDefects(part.heights, n, n, autoOptions);
            throwIfInterrupted();
            const DefectMap p = detectDefects(part.heights, n, n, paperOptions);
            tAuto.push_back(a.seconds);
            tPaper.push_back(p.seconds);
            task.advance();
            row.markedAuto = a.markedFraction();
            row.markedPaper = p.markedFraction();
            if (r == 0) {
                const std::vector<uint8_t> negatives{kTruthChatter};
                const DefectScore s =
                    scoreDefectMap(a.map, part.truth, truthLegend(part.truth), negatives);
                row.precision = s.overall.precision;
                row.recall = s.overall.recall;
            }
        }
        row.secondsAuto = median(tAuto);
        row.secondsPaper = median(tPaper);
        row.ratio = row.secondsPaper > 0 ? row.secondsAuto / row.secondsPaper : 0.0;
        result.rows.push_back(row);
    }
    return result;
}

std::string DefectMapBenchResult::csv() const {
    std::ostringstream os;
    os << "size,repeats,seconds_auto,seconds_paper,ratio,marked_auto,marked_paper,precision,"
          "recall\n";
    for (const DefectMapBenchRow& r : rows)
        os << r.size << ',' << options.repeats << ',' << r.secondsAuto << ',' << r.secondsPaper
           << ',' << r.ratio << ',' << r.markedAuto << ',' << r.markedPaper << ',' << r.precision
           << ',' << r.recall << '\n';
    return os.str();
}

}  // namespace sl
