// scratchlight precompute SCENE.json [--spp N|auto] [--rgb] [--halves] [--rows A:B] [-o part.tm]
#include <cstdio>
#include <filesystem>
#include <memory>

#include "app/host/ExternalRenderer.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/Transport.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "cli/TraceOptions.h"
#include "core/Error.h"
#include "core/Registry.h"

namespace sl::cli {

namespace {

struct PrecomputeArgs {
    std::string scene, out = "part.tm", rows;
    PrecomputeOptions p;
    std::vector<std::string> overrides;
    RendererKind renderer = RendererKind::Builtin;
    ExternalRendererOptions external;
};

/// --rows A:B into the options' row range.
void parseRows(const std::string& v, PrecomputeOptions& p) {
    const auto rows = parseColonPair<int>(v);
    if (!rows) throw UsageError("--rows " + v + ": expected A:B (image rows A to B-1, e.g. 0:256)");
    p.rowBegin = rows->first;
    p.rowEnd = rows->second;
}

int runPrecompute(PrecomputeArgs a) {
    if (std::filesystem::path(a.out).extension() != ".tm")
        throw UsageError("output '" + a.out + "' must end in .tm");
    if (!a.rows.empty()) parseRows(a.rows, a.p);
    if (a.renderer != RendererKind::Builtin) {
        if (a.p.autoMaxDepth || a.p.autoSpp)
            throw UsageError(
                "--max-depth auto and --spp auto measure our tracer; an external renderer "
                "keeps its own path length and samples: drop them");
        if (a.p.rgb || a.p.sampleSets != 1 || !a.rows.empty())
            throw UsageError("--renderer " +
                             std::string(registryRow(rendererKindTable(), a.renderer).name) +
                             " builds a gray T from basis renders: drop --rgb, --halves and "
                             "--rows");
        BasisTransportOptions bo;
        bo.threads = a.p.threads;
        bo.seed = a.p.seed.value_or(0);
        bo.cacheDir = cacheDirectory(CacheLocation{});
        const BasisTransportResult r =
            precomputeBasisToFile(a.scene, a.overrides, a.renderer, a.external, bo, a.out);
        const TransportMatrix& t = r.file.matrix;
        std::printf(
            "transport matrix %dx%d px x %dx%d texels from %d basis renders (%d rendered, %d "
            "from the cache) in %.1f s; linearity error %.2g; T.E against a direct render of a "
            "random light: relative error %.2g\n",
            t.width, t.height, t.envWidth, t.envHeight, r.rendered + r.reused, r.rendered, r.reused,
            r.seconds, r.linearityError, r.directError);
        std::printf("wrote %s (fingerprint %s)\n", a.out.c_str(),
                    r.file.provenance.fingerprint.c_str());
        return kOk;
    }
    TransportSource s = precomputeToFile(a.scene, a.p, a.out, a.overrides);
    if (s.autoDepth)
        std::printf("max_depth %d: %s\n", s.autoDepth->maxDepth, s.autoDepth->reason.c_str());
    if (s.autoSpp) std::printf("spp %d: %s\n", s.autoSpp->spp, s.autoSpp->reason.c_str());
    std::printf("%s\n", describeTransport(s).c_str());
    std::printf("wrote %s (fingerprint %s)\n", a.out.c_str(),
                s.file.provenance.fingerprint.c_str());
    return kOk;
}

}  // namespace

void registerPrecompute(CLI::App& app, std::function<int()>& run) {
    auto a = std::make_shared<PrecomputeArgs>();
    CLI::App* c = app.add_subcommand(
        "precompute", "Trace the scene once into its light-transport matrix T (I = T·E)");
    c->add_option("scene", a->scene, "Scene file (JSON)")->required();
    addTraceOptions(c, a->p, a->overrides);
    c->add_flag("--rgb", a->p.rgb, "Store RGB T (3 blocks) instead of luminance T");
    addRendererOptions(c, a->renderer, a->external);
    c->add_flag_function(
        "--halves", [a](std::int64_t) { a->p.sampleSets = 2; },
        "Store the two half-sample matrices T_a, T_b (for --objective unbiased and held-out "
        "estimates)");
    c->add_option("--rows", a->rows,
                  "Trace image rows A to B-1 only (A:B): a shard of T for a cluster; list "
                  "the shards in a .shards file to use them as one T (docs/CLUSTER.md)");
    c->add_option("-o,--output", a->out, "Output transport-matrix file (.tm)")
        ->capture_default_str();
    c->callback([a, &run] { run = [a] { return runPrecompute(*a); }; });
}

}  // namespace sl::cli
