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
    autoOptions.measured = false;
    DefectMapOptions measuredOptions = autoOptions;
    measuredOptions.measured = true;
    DefectMapOptions paperOptions = o.map;
    paperOptions.method = DefectMethod::Paper;
    ProgressTask task("bench defectmap", static_cast<double>(o.sizes.size()) * o.repeats);
    for (int n : o.sizes) {
        SurfaceSpec spec = testPartSpec(TestPart::BallEnd);
        spec.width = spec.height = n;
        const GeneratedSurface part = generateSurface(spec);
        DefectMapBenchRow row;
        row.size = n;
        std::vector<double> tAuto, tMeasured, tPaper;
        const std::vector<uint8_t> negatives{kTruthChatter};
        const auto score = [&](const DefectMap& m) {
            return scoreDefectMap(m.map, part.truth, truthLegend(part.truth), negatives).overall;
        };
        for (int r = 0; r < o.repeats; ++r) {
            throwIfInterrupted();
            const DefectMap a = detectDefects(part.heights, n, n, autoOptions);
            tAuto.push_back(a.seconds);
            row.markedAuto = a.markedFraction();
            if (r == 0) {
                const auto s = score(a);
                row.precision = s.precision;
                row.recall = s.recall;
            }
            if (o.measured) {
                throwIfInterrupted();
                const DefectMap m = detectDefects(part.heights, n, n, measuredOptions);
                tMeasured.push_back(m.seconds);
                row.markedMeasured = m.markedFraction();
                if (r == 0) {
                    const auto s = score(m);
                    row.precisionMeasured = s.precision;
                    row.recallMeasured = s.recall;
                }
            }
            throwIfInterrupted();
            const DefectMap p = detectDefects(part.heights, n, n, paperOptions);
            tPaper.push_back(p.seconds);
            row.markedPaper = p.markedFraction();
            task.advance();
        }
        row.secondsAuto = median(tAuto);
        row.secondsMeasured = tMeasured.empty() ? 0.0 : median(tMeasured);
        row.secondsPaper = median(tPaper);
        row.ratio = row.secondsPaper > 0 ? row.secondsAuto / row.secondsPaper : 0.0;
        row.ratioMeasured = row.secondsPaper > 0 ? row.secondsMeasured / row.secondsPaper : 0.0;
        result.rows.push_back(row);
    }
    return result;
}

std::string DefectMapBenchResult::csv() const {
    std::ostringstream os;
    os << "size,repeats,seconds_auto,seconds_measured,seconds_paper,ratio,ratio_measured,"
          "marked_auto,marked_measured,marked_paper,precision,recall,precision_measured,"
          "recall_measured\n";
    for (const DefectMapBenchRow& r : rows)
        os << r.size << ',' << options.repeats << ',' << r.secondsAuto << ',' << r.secondsMeasured
           << ',' << r.secondsPaper << ',' << r.ratio << ',' << r.ratioMeasured << ','
           << r.markedAuto << ',' << r.markedMeasured << ',' << r.markedPaper << ',' << r.precision
           << ',' << r.recall << ',' << r.precisionMeasured << ',' << r.recallMeasured << '\n';
    return os.str();
}

}  // namespace sl
