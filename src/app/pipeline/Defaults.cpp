#include "app/pipeline/Defaults.h"

#include "io/SceneFile.h"
#include "io/TransportFile.h"

namespace sl {

OptimizeDefaults optimizeDefaults() {
    return {};
}

ObjectiveKind defaultObjective(bool defectsNamed, std::optional<int> planes) {
    if (planes && *planes != 2) return ObjectiveKind::Paper;
    const OptimizeDefaults d = optimizeDefaults();
    return defectsNamed ? d.objectiveWithDefects : d.objective;
}

OptimizerOptions optimizeJobOptimizerOptions() {
    OptimizerOptions o;
    o.method = optimizeDefaults().method;
    o.iterations = 0;
    return o;
}

OptimizerOptions resolveOptimizer(OptimizerOptions requested) {
    const OptimizerMethodRow& row = methodRow(requested.method);
    requested.method = row.runs;
    if (requested.iterations == 0) requested.iterations = row.defaultBudget;
    return requested;
}

OptimizerOptions withJndStall(OptimizerOptions opt, ObjectiveKind kind,
                              const ObjectiveOptions& objective) {
    const bool jndUnits = objective.defectMeasure == DefectMeasure::Jnd ||
                          objective.defectMeasure == DefectMeasure::Both;
    if (kind == ObjectiveKind::Defects && jndUnits && opt.stallEvaluations == 0) {
        opt.stallEvaluations = kJndStallEvaluations;
        opt.stallTolerance = kJndStallTolerance;
    }
    return opt;
}

OptimizerOptions resolveOptimizer(OptimizerOptions requested, ObjectiveKind kind,
                                  const ObjectiveOptions& objective) {
    const bool budgetGiven = requested.iterations != 0;
    const OptimizerOptions resolved = resolveOptimizer(requested);
    return budgetGiven ? resolved : withJndStall(resolved, kind, objective);
}

InputTransport transportOfInput(const std::filesystem::path& input,
                                const std::vector<std::string>& sceneOverrides,
                                const PrecomputeOptions& trace,
                                const std::filesystem::path& cacheDir) {
    InputTransport in;
    if (isTransportFile(input)) {
        in.transport.file = readTransportFile(input);
        in.transport.path = input;
    } else {
        in.scene = loadScene(input, sceneOverrides);
        in.transport = transportForScene(*in.scene, trace, cacheDir);
    }
    return in;
}

}  // namespace sl
