#include "app/pipeline/Transport.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <nlohmann/json.hpp>

#include "app/pipeline/Cache.h"
#include "app/pipeline/HeldOut.h"
#include "core/Error.h"
#include "core/Md5.h"
#include "core/Progress.h"
#include "core/Rng.h"
#include "core/Stopwatch.h"
#include "core/Text.h"
#include "io/SceneFile.h"
#include "objective/Objective.h"
#include "render/Render.h"
#include "scene/Scene.h"
#include "transport/TransportSink.h"

namespace sl {

namespace {

TransportSource trace(const Scene& scene, const RenderOptions& ro, const TransportProvenance& prov,
                      bool rgb, const std::string& label, const std::filesystem::path& out,
                      const Stopwatch& clock, bool result = false) {
    ProgressTask task(label + " (" + std::to_string(scene.camera.width()) + "x" +
                          std::to_string(scene.camera.height()) + " px, " + std::to_string(ro.spp) +
                          " spp)",
                      1);
    RenderOptions withProgress = ro;
    withProgress.progress = task.fraction();
    PrecomputeResult r = precomputeTransport(scene, withProgress, rgb ? 3 : 1);
    TransportSource s;
    s.secondsTrace = r.summary.seconds;
    s.trace = r.summary;
    if (!out.empty()) writeTransportFile(out, r.matrix, prov, result);
    s.file.matrix = std::move(r.matrix);
    s.file.provenance = prov;
    s.path = out;
    s.secondsTotal = clock.seconds();
    return s;
}

}  // namespace

std::vector<TransportSource> transportSetForScene(const Scene& scene,
                                                  const PrecomputeOptions& options, int count,
                                                  const std::filesystem::path& cacheDir) {
    if (count < 1) throw inputError("estimates", "must be >= 1, got " + std::to_string(count));
    const uint64_t base = options.seed ? *options.seed : scene.desc.render.seed;
    std::vector<TransportSource> set;
    for (int k = 0; k < count; ++k) {
        PrecomputeOptions o = options;
        o.seed = base + static_cast<uint64_t>(k);
        set.push_back(transportForScene(scene, o, cacheDir));
    }
    return set;
}

std::string describeTransport(const TransportSource& s) {
    const TransportMatrix& t = s.file.matrix;
    char buf[512];
    std::snprintf(
        buf, sizeof buf,
        "transport matrix %dx%d px x %dx%d texels, %s T, %s, nnz %zu (density %.4f), %.1f MB",
        t.width, t.height, t.envWidth, t.envHeight, t.channels == 3 ? "RGB" : "gray",
        t.storage == TransportStorage::Sparse ? "CSR" : "dense", t.nnz(), t.density(),
        static_cast<double>(t.bytes()) / 1e6);
    std::string out = buf;
    if (s.trace.rays) {
        std::snprintf(buf, sizeof buf, "\ntraced %llu rays in %.3f s (%.2f Mrays/s), total %.3f s",
                      static_cast<unsigned long long>(s.trace.rays), s.trace.seconds,
                      s.trace.raysPerSecond() / 1e6, s.secondsTotal);
        out += buf;
    }
    return out;
}

TransportFile readShardOfRank(const std::filesystem::path& list, const Communicator& ranks,
                              RowShard* rows) {
    if (!ranks.distributed()) {
        TransportFile f = readTransportFile(list);
        if (rows) *rows = RowShard{&ranks, 0, static_cast<size_t>(f.matrix.height)};
        return f;
    }
    if (list.extension() != ".shards")
        throw inputError(list.string(),
                         "is one transport matrix; over " + std::to_string(ranks.size()) +
                             " MPI ranks every rank needs a shard of it",
                         "list " + std::to_string(ranks.size()) + " shards (`precompute " +
                             option("rows") + " A:B`) in a .shards file");
    const std::vector<std::filesystem::path> files = shardListFiles(list);
    if (files.size() != static_cast<size_t>(ranks.size()))
        throw inputError(list.string(),
                         "lists " + std::to_string(files.size()) + " shards for " +
                             std::to_string(ranks.size()) + " MPI ranks",
                         "run one rank per shard: mpirun -np " + std::to_string(files.size()));
    const auto me = static_cast<size_t>(ranks.rank());
    TransportFile f = readTransportFile(files[me]);
    const ShardOf mine = shardOf(f, files[me].string());
    // Every rank's rows, dimensions and inputs' fingerprint (32 hex digits as 8 exact doubles).
    constexpr size_t kFacts = 14;
    std::vector<double> facts(kFacts);
    const TransportMatrix& t = f.matrix;
    facts[0] = mine.rowBegin;
    facts[1] = mine.rowEnd;
    facts[2] = t.width;
    facts[3] = t.height;
    facts[4] = static_cast<double>(t.cols());
    facts[5] = t.channels * 16 + t.planes;
    for (size_t k = 0; k < 8; ++k)
        facts[6 + k] =
            static_cast<double>(std::stoul(mine.fingerprint.substr(4 * k, 4), nullptr, 16));
    const std::vector<double> all = allGather(ranks, facts);
    std::vector<std::array<int, 2>> ranges;
    std::vector<std::string> names;
    for (size_t r = 0; r < files.size(); ++r) {
        const double* x = all.data() + r * kFacts;
        if (!std::equal(x + 2, x + kFacts, all.data() + 2))
            throw inputError(
                files[r].string(),
                "was traced with other inputs than " + files[0].string() +
                    " (scene, camera, material, spp, seed or max_depth)",
                "trace every shard of " + list.string() + " with the same scene and options");
        ranges.push_back({static_cast<int>(x[0]), static_cast<int>(x[1])});
        names.push_back(files[r].string());
    }
    shardRowOwners(ranges, t.height, list.string(), names);
    const RowShard shard{&ranks, static_cast<size_t>(mine.rowBegin),
                         static_cast<size_t>(mine.rowEnd)};
    std::vector<double> mask(f.matrix.objectMask.begin(), f.matrix.objectMask.end());
    shard.gatherImage(mask, static_cast<size_t>(t.width));
    for (size_t q = 0; q < mask.size(); ++q) f.matrix.objectMask[q] = mask[q] != 0 ? 1 : 0;
    if (rows) *rows = shard;
    f.provenance.inputs = mine.inputs;
    f.provenance.fingerprint = mine.fingerprint;
    return f;
}

bool isTransportFile(const std::filesystem::path& input) {
    return input.extension() == ".tm" || input.extension() == ".shards";
}

std::optional<DepthChoice> resolveMaxDepth(const Scene& scene, PrecomputeOptions& o) {
    if (!o.autoMaxDepth) return std::nullopt;
    AutoDepthOptions a;
    a.threads = o.threads;
    DepthChoice c = autoMaxDepth(scene, a);
    o.maxDepth = c.maxDepth;
    o.autoMaxDepth = false;
    return c;
}

std::optional<SppChoice> resolveSpp(const Scene& scene, PrecomputeOptions& o,
                                    const std::vector<uint8_t>& region,
                                    const std::filesystem::path& cacheDir) {
    if (!o.autoSpp) return std::nullopt;
    if (!(o.sppTolerance > 0 && o.sppTolerance < 1))
        throw inputError(option("tolerance"), "is " + formatNumber(o.sppTolerance, 3),
                         "use a relative noise in (0, 1), e.g. 0.05");
    PrecomputeOptions pilot = o;
    pilot.autoSpp = false;
    pilot.spp = kSppAutoPilot;
    pilot.sampleSets = 2;
    pilot.rgb = false;
    pilot.label = "spp auto: pilot";
    const TransportSource src = transportForScene(scene, pilot, cacheDir);
    const TransportMatrix& t = src.file.matrix;
    std::vector<uint8_t> mask = t.objectMask;
    if (!region.empty()) mask = intersectMasks(mask, region);
    if (std::none_of(mask.begin(), mask.end(), [](uint8_t v) { return v != 0; }))
        throw inputError("scene", "the pilot trace of spp auto sees none of the part",
                         "point the camera at the part, or give " + option("spp"));
    ObjectiveOptions oo;
    oo.lambda = 0;  // the regulariser's gradient has no noise
    const ImageObjective lgrad(t.width, t.height, mask, oo);
    const std::vector<double> E(t.cols(), 0.5);
    std::vector<double> y(t.rows()), dy(t.rows());
    std::vector<std::vector<double>> g(2, std::vector<double>(t.cols()));
    for (int plane = 0; plane < 2; ++plane) {
        t.applyLuminance(E, y, plane);
        lgrad.evaluate(y, E, dy);
        t.applyTransposeLuminance(dy, g[static_cast<size_t>(plane)], plane);
    }
    double diff = 0, sum = 0;
    for (size_t k = 0; k < t.cols(); ++k) {
        diff += (g[0][k] - g[1][k]) * (g[0][k] - g[1][k]);
        sum += (g[0][k] + g[1][k]) * (g[0][k] + g[1][k]);
    }
    SppChoice c;
    c.pilotSpp = kSppAutoPilot;
    c.pilotNoise = sum > 0 ? std::sqrt(diff / sum) : 1.0;
    int n = kSppAutoPilot;
    auto noiseAt = [&](int spp) { return c.pilotNoise * std::sqrt(double(kSppAutoPilot) / spp); };
    while (n < kSppAutoMax && noiseAt(n) > o.sppTolerance) n *= 2;
    c.spp = n;
    c.chosenNoise = noiseAt(n);
    c.reason = "the gradient's relative noise is " + formatNumber(c.pilotNoise, 3) + " at " +
               std::to_string(kSppAutoPilot) + " spp (two independent halves of a pilot, " +
               formatNumber(src.secondsTotal, 2) + " s), so " + formatNumber(c.chosenNoise, 3) +
               " at " + std::to_string(n) + " spp";
    c.reason += noiseAt(n) <= o.sppTolerance
                    ? ", the fewest (a power of two) within the tolerance " +
                          formatNumber(o.sppTolerance, 3)
                    : ", above the tolerance " + formatNumber(o.sppTolerance, 3) +
                          " but the most spp auto takes";
    o.spp = n;
    o.autoSpp = false;
    return c;
}

RenderOptions traceOptions(const Scene& scene, const PrecomputeOptions& o) {
    return traceOptions(renderOptionsFor(scene), scene.camera.height(), o);
}

RenderOptions traceOptions(const RenderOptions& sceneRender, int imageHeight,
                           const PrecomputeOptions& o) {
    if (o.autoSpp) throw std::logic_error("traceOptions: resolve spp auto first (resolveSpp)");
    if (o.autoMaxDepth)
        throw std::logic_error("traceOptions: resolve max_depth auto first (resolveMaxDepth)");
    RenderOptions r = sceneRender;
    if (o.spp) r.spp = *o.spp;
    if (o.maxDepth) r.maxDepth = *o.maxDepth;
    if (o.sampling) r.sampling = *o.sampling;
    if (!o.pixels.empty()) {  // their size is the tracer's to check
        if (std::none_of(o.pixels.begin(), o.pixels.end(), [](uint8_t f) { return f != 0; }))
            throw std::invalid_argument("traceOptions: no pixel to trace");
        r.pixels = o.pixels;
    }
    r.sppScale = o.sppScale;  // its size is the tracer's to check
    if (o.rowBegin != 0 || o.rowEnd != 0) {
        const int H = imageHeight;
        if (o.rowBegin < 0 || o.rowEnd > H || o.rowBegin >= o.rowEnd)
            throw inputError(option("rows"),
                             std::to_string(o.rowBegin) + ":" + std::to_string(o.rowEnd) +
                                 " is not a row range of the " + std::to_string(H) + "-row image",
                             "use A:B with 0 <= A < B <= " + std::to_string(H));
        r.rowBegin = o.rowBegin;
        r.rowEnd = o.rowEnd;
    }
    if (o.seed) r.seed = *o.seed;
    r.threads = o.threads;
    r.sampleSets = o.sampleSets;
    return r;
}

namespace {

/// The cache's T of these inputs, when it is there and reads (a damaged one is warned about).
std::optional<TransportSource> readCachedTransport(const TransportProvenance& prov,
                                                   const std::filesystem::path& cacheDir,
                                                   const Stopwatch& clock) {
    const auto cached = transportCachePath(cacheDir, prov.fingerprint);
    if (!std::filesystem::exists(cached)) return std::nullopt;
    try {
        TransportSource s;
        s.file = readTransportFile(cached, prov.fingerprint);
        s.path = cached;
        s.cacheHit = true;
        touchCacheFile(cached);  // its last use, for the cache's size cap (app/pipeline/Cache.h)
        s.secondsTotal = clock.seconds();
        spdlog::info("transport matrix from cache {}", cached.string());
        return s;
    } catch (const InputError& e) {
        spdlog::warn("ignoring cached transport matrix: {}", e.what());
    }
    return std::nullopt;
}

}  // namespace

TransportSource precomputeToFile(const std::filesystem::path& file,
                                 const PrecomputeOptions& options, const std::filesystem::path& out,
                                 const std::vector<std::string>& sceneOverrides) {
    const Stopwatch clock;
    auto scene = loadScene(file, sceneOverrides);
    PrecomputeOptions resolved = options;
    const auto depth = resolveMaxDepth(*scene, resolved);
    const auto spp = resolveSpp(*scene, resolved, {}, {});
    const RenderOptions ro = traceOptions(*scene, resolved);
    TransportSource s = trace(*scene, ro, transportProvenance(*scene, ro, options.rgb ? 3 : 1),
                              options.rgb, options.label, out, clock, /*result=*/true);
    s.autoDepth = depth;
    s.autoSpp = spp;
    return s;
}

TransportSource transportForScene(const Scene& scene, const PrecomputeOptions& options,
                                  const std::filesystem::path& cacheDir) {
    const Stopwatch clock;
    const RenderOptions ro = traceOptions(scene, options);
    const TransportProvenance prov = transportProvenance(scene, ro, options.rgb ? 3 : 1);
    if (cacheDir.empty()) return trace(scene, ro, prov, options.rgb, options.label, {}, clock);
    if (auto s = readCachedTransport(prov, cacheDir, clock)) return std::move(*s);
    return trace(scene, ro, prov, options.rgb, options.label,
                 transportCachePath(cacheDir, prov.fingerprint), clock);
}

std::optional<TransportSource> cachedTransport(const nlohmann::json& sceneInputs,
                                               const RenderOptions& sceneRender,
                                               const PrecomputeOptions& options,
                                               const std::filesystem::path& cacheDir) {
    const Stopwatch clock;
    if (cacheDir.empty()) return std::nullopt;
    const int height = sceneInputs.at("camera").at("height").get<int>();
    const RenderOptions ro = traceOptions(sceneRender, height, options);
    return readCachedTransport(transportProvenance(sceneInputs, ro, options.rgb ? 3 : 1), cacheDir,
                               clock);
}

TransportMatrix meanOfEstimates(const TransportMatrix& a0, const TransportMatrix& b0) {
    if (!sameShape(a0, b0))
        throw std::invalid_argument("meanOfEstimates: the estimates are not of the same T");
    // Sparse views (a dense one converted on a copy).
    std::optional<TransportMatrix> ca, cb;
    if (a0.storage != TransportStorage::Sparse) (ca = a0)->toSparse();
    if (b0.storage != TransportStorage::Sparse) (cb = b0)->toSparse();
    const TransportMatrix& a = ca ? *ca : a0;
    const TransportMatrix& b = cb ? *cb : b0;
    TransportMatrix t = emptySparseOfShape(a);
    t.threads = a.threads;
    const size_t rows = a.rows(), st = static_cast<size_t>(a.stride());
    t.colIdx.reserve(a.colIdx.size() + b.colIdx.size());
    t.values.reserve(a.values.size() + b.values.size());
    auto push = [&](uint16_t col, const float* va, const float* vb) {
        t.colIdx.push_back(col);
        for (size_t k = 0; k < st; ++k)
            t.values.push_back(static_cast<float>(
                0.5 * ((va ? double(va[k]) : 0.0) + (vb ? double(vb[k]) : 0.0))));
    };
    for (size_t r = 0; r < rows; ++r) {
        uint64_t i = a.rowPtr[r], j = b.rowPtr[r];
        const uint64_t ie = a.rowPtr[r + 1], je = b.rowPtr[r + 1];
        while (i < ie || j < je) {
            const bool takeA = j >= je || (i < ie && a.colIdx[i] <= b.colIdx[j]);
            const bool takeB = i >= ie || (j < je && b.colIdx[j] <= a.colIdx[i]);
            push(takeA ? a.colIdx[i] : b.colIdx[j], takeA ? &a.values[i * st] : nullptr,
                 takeB ? &b.values[j * st] : nullptr);
            i += takeA;
            j += takeB;
        }
        t.rowPtr[r + 1] = t.colIdx.size();
        t.objectMask[r] = a.objectMask[r] && b.objectMask[r] ? 1 : 0;
    }
    chooseStorage(t);
    return t;
}

uint64_t doublingSeed(uint64_t seed, int spp) {
    return mix64(seed ^ mix64(0x646F75626C65ULL + static_cast<uint64_t>(spp)));  // "double"
}

namespace {

/// The chunks of transportInDoublings: how many doublings from base to spp (0: none).
int doublings(int spp, int base) {
    int k = 0;
    if (base < 2 || spp <= base) return 0;
    while (spp > base && spp % 2 == 0) spp /= 2, ++k;
    return spp == base ? k : 0;
}

/// The provenance of the estimate transportInDoublings gives, without tracing.
TransportProvenance doubledProvenance(const Scene& scene, const PrecomputeOptions& o, int base) {
    const int spp = o.spp.value_or(scene.desc.render.spp);
    if (doublings(spp, base) == 0)
        return transportProvenance(scene, traceOptions(scene, o), o.rgb ? 3 : 1);
    PrecomputeOptions half = o, chunk = o;
    half.spp = chunk.spp = spp / 2;
    const uint64_t seed = o.seed.value_or(scene.desc.render.seed);
    chunk.seed = doublingSeed(seed, spp / 2);
    const TransportProvenance ph = doubledProvenance(scene, half, base);
    const TransportProvenance pc =
        transportProvenance(scene, traceOptions(scene, chunk), o.rgb ? 3 : 1);
    TransportProvenance p = ph;
    p.spp = spp;
    const std::string both = ph.fingerprint + "+" + pc.fingerprint;
    p.fingerprint = md5Hex(both.data(), both.size());
    nlohmann::json in = nlohmann::json::parse(ph.inputs);
    if (in.contains("render")) in["render"]["spp"] = spp;
    in["doubled"] = {
        {"of", ph.fingerprint}, {"chunk", pc.fingerprint}, {"chunk_seed", *chunk.seed}};
    p.inputs = in.dump();
    return p;
}

}  // namespace

TransportSource transportInDoublings(const Scene& scene, const PrecomputeOptions& options, int base,
                                     const std::filesystem::path& cacheDir) {
    const int spp = options.spp.value_or(scene.desc.render.spp);
    if (doublings(spp, base) == 0) return transportForScene(scene, options, cacheDir);
    const Stopwatch clock;
    const TransportProvenance prov = doubledProvenance(scene, options, base);
    const auto cached =
        cacheDir.empty() ? std::filesystem::path() : transportCachePath(cacheDir, prov.fingerprint);
    if (!cached.empty())
        if (auto s = readCachedTransport(prov, cacheDir, clock)) return std::move(*s);
    PrecomputeOptions half = options, chunk = options;
    half.spp = chunk.spp = spp / 2;
    chunk.seed = doublingSeed(options.seed.value_or(scene.desc.render.seed), spp / 2);
    const TransportSource h = transportInDoublings(scene, half, base, cacheDir);
    const TransportSource c = transportForScene(scene, chunk, cacheDir);
    TransportSource s;
    s.file.matrix = meanOfEstimates(h.file.matrix, c.file.matrix);
    s.file.provenance = prov;
    s.cacheHit = h.cacheHit && c.cacheHit;
    s.secondsTrace = h.secondsTrace + c.secondsTrace;
    s.trace = c.trace;
    if (!cached.empty()) {
        writeTransportFile(cached, s.file.matrix, prov);
        s.path = cached;
    }
    s.secondsTotal = clock.seconds();
    return s;
}

std::unique_ptr<Scene> sceneOfTransport(const TransportFile& f, const std::string& purpose) {
    const auto in = nlohmann::json::parse(f.provenance.inputs);
    if (!in.contains("scene_file"))
        throw inputError(purpose, "needs the scene, and the transport matrix does not record it",
                         "pass the scene file instead of the .tm");
    auto sc = loadScene(std::filesystem::path(in.at("scene_file").get<std::string>()),
                        in.value("scene_overrides", std::vector<std::string>{}));
    if (sc->camera.width() != f.matrix.width || sc->camera.height() != f.matrix.height)
        throw inputError(sc->desc.file.string(), "its camera does not match the transport matrix",
                         "recompute the transport matrix");
    return sc;
}

}  // namespace sl
