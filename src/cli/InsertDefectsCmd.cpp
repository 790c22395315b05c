// scratchlight insert-defects HEIGHTMAP|SCENE.json [--model A|B] [--kinds K,K] [--seed S]
//                            [--depth-sq X | --depth-um D] [--size N] -o OUT.exr
// Parses the options and prints what was inserted; the work is app/jobs/InsertDefectsJob.h and
// synth/DefectInsert.h.
#include <cstdio>
#include <memory>
#include <sstream>

#include "app/jobs/InsertDefectsJob.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Registry.h"

namespace sl::cli {

namespace {

struct ModelRow {
    DefectModel value;
    const char* name;
    const char* help;
};
constexpr ModelRow kModels[] = {
    {DefectModel::A, "A", "scratches with pile-up rims, pits with a rim, burrs (tuned on)"},
    {DefectModel::B, "B",
     "asymmetric gouges, chains of small pits, dents with no rim (cracks when named)"},
};

int runInsert(const InsertDefectsJobOptions& o) {
    const InsertDefectsJobSummary s = runInsertDefectsJob(o);
    std::printf(
        "%dx%d samples at %.6g mm%s; texture Sq %.4g um; defects %.4g um deep, faint ones "
        "%.4g um (unlabelled)\n",
        s.width, s.height, s.pitch,
        s.resampled != 1 ? (" (resampled by " + std::to_string(s.resampled) + ")").c_str() : "",
        s.sq * 1e3, s.depth * 1e3, s.faintDepth * 1e3);
    std::printf("%-10s %8s %10s %12s %8s %10s\n", "kind", "labelled", "depth_um", "centre", "size",
                "samples");
    for (const InsertedDefect& d : s.result.defects) {
        char centre[32];
        std::snprintf(centre, sizeof centre, "%.0f,%.0f", d.x, d.z);
        std::printf("%-10s %8s %10.4g %12s %8.2f %10zu\n", insertKindRow(d.kind).name,
                    d.labelled ? "yes" : "faint", d.depth * 1e3, centre, d.size, d.samples);
    }
    if (s.result.skipped > 0)
        std::printf("%d defects found no room and were left out\n", s.result.skipped);
    for (const auto& f : s.written) std::printf("wrote %s\n", f.string().c_str());
    return kOk;
}

}  // namespace

void registerInsertDefects(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<InsertDefectsJobOptions>();
    CLI::App* c = app.add_subcommand(
        "insert-defects",
        "Insert defects of known shape into a height map (or a scene's) and write it with its "
        "truth labels, legend and a scene file, as gen-surface does");
    addHeightSourceInput(c, a->input, a->sceneOverrides,
                         "Height map (X3P, SDF, EXR, ...) or scene file (JSON)");
    c->add_option_function<std::string>(
         "-o,--output", [a](const std::string& v) { a->output = v; },
         "Height map to write (.exr, float32 mm); beside it <stem>-truth.png, <stem>-truth.json "
         "and the scene <stem>.json")
        ->default_str("defects.exr");
    addChoice(c, "--model", a->spec.model, std::span<const ModelRow>(kModels),
              "Defect model (default A)");
    c->add_option_function<std::string>(
        "--kinds",
        [a](const std::string& v) {
            a->spec.kinds.clear();
            std::stringstream ss(v);
            std::string k;
            while (std::getline(ss, k, ','))
                if (!k.empty()) a->spec.kinds.push_back(parseInsertKind(k, "--kinds"));
        },
        "Comma-separated kinds of the model (default: its three; crack only when named): " +
            registryNames(insertKindTable()));
    c->add_option("--seed", a->spec.seed, "Random seed of the placement and shapes")
        ->capture_default_str();
    auto* dsq = c->add_option("--depth-sq", a->depthSq,
                              "Defect depth as a multiple of the texture's Sq (about its "
                              "quadratic form)")
                    ->capture_default_str();
    c->add_option("--depth-um", a->depthUm, "Defect depth in micrometres (instead of --depth-sq)")
        ->excludes(dsq);
    c->add_option("--faint-sq", a->faintSq,
                  "Depth of the faint, unlabelled defects as a multiple of Sq")
        ->capture_default_str();
    c->add_option("--count", a->spec.count, "Labelled defects per kind")->capture_default_str();
    c->add_option("--faint", a->spec.faint, "Faint (unlabelled) defects per kind")
        ->capture_default_str();
    c->add_option("--size-scale", a->spec.sizeScale,
                  "Multiplies the defects' widths and radii (in samples)")
        ->capture_default_str();
    c->add_option("--margin", a->spec.margin, "Samples from the map's edges kept clear")
        ->capture_default_str();
    c->add_option("--size", a->size,
                  "Working size: resample the height map to N samples on its longer side first "
                  "(box average; 0: as read)")
        ->capture_default_str();
    c->add_option("--pitch", a->pitch, "Sample spacing in mm, for a map that carries none");
    c->add_option("--image-size", a->imageSize,
                  "Scene file: camera image width and height in pixels (default: the scene's)")
        ->check(inRange(1, 16384));
    c->callback([a, &run] { run = [a] { return runInsert(*a); }; });
}

}  // namespace sl::cli
