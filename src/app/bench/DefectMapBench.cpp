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
        const auto legend = truthLegend(part.truth);
        // one method's map: its seconds and marked share recorded, the map returned
        const auto runMethod = [&](const DefectMapOptions& mo, std::vector<double>& seconds,
                                   double& marked) {
            throwIfInterrupted();
            DefectMap m = detectDefects(part.heights, n, n, mo);
            seconds.push_back(m.seconds);
            marked = m.markedFraction();
            return m;
        };
        const auto score = [&](const DefectMap& m, double& precision, double& recall) {
            const DefectScoreRow s = scoreDefectMap(m.map, part.truth, legend, negatives).overall;
            precision = s.precision;
            recall = s.recall;
        };
        for (int r = 0; r < o.repeats; ++r) {
            const DefectMap a = runMethod(autoOptions, tAuto, row.markedAuto);
            if (r == 0) score(a, row.precision, row.recall);
            if (o.measured) {
                const DefectMap m = runMethod(measuredOptions, tMeasured, row.markedMeasured);
                if (r == 0) score(m, row.precisionMeasured, row.recallMeasured);
            }
            runMethod(paperOptions, tPaper, row.markedPaper);
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
