#include "io/OptimizeSummary.h"

#include <cmath>
#include <limits>

#include "core/Error.h"
#include "io/InputFile.h"
#include "io/OptimizeOutDir.h"

namespace sl::outdir {

namespace {

using json = nlohmann::json;

/// What a typed key may hold: the check of its value and its name in a message.
struct Kind {
    bool (*fits)(const json&);
    const char* name;
};
constexpr Kind kString{[](const json& v) { return v.is_string(); }, "a string"};
constexpr Kind kNumber{[](const json& v) { return v.is_number(); }, "a number"};
constexpr Kind kBool{[](const json& v) { return v.is_boolean(); }, "true or false"};
constexpr Kind kInteger{[](const json& v) { return v.is_number_integer(); }, "an integer"};
constexpr Kind kObject{[](const json& v) { return v.is_object(); }, "an object"};
constexpr Kind kArray{[](const json& v) { return v.is_array(); }, "an array"};

/// The value at `pointer`, or nullptr when absent or null; InputError naming `where` and the
/// pointer when it is not of `kind`.
const json* take(const json& d, const std::string& pointer, const std::string& where,
                 const Kind& kind) {
    const json::json_pointer p(pointer);
    if (!d.contains(p) || d.at(p).is_null()) return nullptr;
    const json& v = d.at(p);
    if (!kind.fits(v))
        throw inputError(where + " " + pointer,
                         std::string("must be ") + kind.name + ", got " + jsonExcerpt(v, 40),
                         "write the output again with a current optimize");
    return &v;
}

/// The number at `pointer` (NaN when absent or null).
double numberAt(const json& d, const std::string& pointer, const std::string& where) {
    const json* v = take(d, pointer, where, kNumber);
    return v ? v->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

/// The string at `pointer` ("" when absent or null).
std::string stringAt(const json& d, const std::string& pointer, const std::string& where) {
    const json* v = take(d, pointer, where, kString);
    return v ? v->get<std::string>() : std::string();
}

/// A judge score at `at` (app/pipeline/Judge.h toJson), or none when absent.
std::optional<JudgedLight> judgedAt(const json& d, const std::string& at,
                                    const std::string& where) {
    if (!take(d, at, where, kObject)) return std::nullopt;
    JudgedLight j;
    j.unbiased = numberAt(d, at + "/unbiased", where);
    j.eq2 = numberAt(d, at + "/eq2", where);
    j.brightness = numberAt(d, at + "/brightness", where);
    j.meanE = numberAt(d, at + "/mean_E", where);
    j.sparsity = numberAt(d, at + "/sparsity", where);
    if (const json* regions = take(d, at + "/visibility", where, kArray)) {
        j.regions.emplace();
        for (size_t k = 0; k < regions->size(); ++k) {
            const std::string r = at + "/visibility/" + std::to_string(k);
            take(d, r, where, kObject);
            JudgedRegion g;
            g.name = stringAt(d, r + "/name", where);
            const double value = numberAt(d, r + "/value", where);
            g.value = std::isfinite(value) ? static_cast<int>(value) : 0;
            const double pixels = numberAt(d, r + "/pixels", where);
            g.pixels = std::isfinite(pixels) ? pixels : 0.0;
            g.visibility = numberAt(d, r + "/visibility", where);
            g.jnd = numberAt(d, r + "/jnd", where);
            g.contrast = numberAt(d, r + "/contrast", where);
            j.regions->push_back(std::move(g));
        }
    }
    if (take(d, at + "/se", where, kObject))
        j.leastVisibleJndSe = numberAt(d, at + "/se/least_visible_jnd", where);
    return j;
}

ComparedLight lightAt(const json& d, const std::string& at, const std::string& where) {
    ComparedLight l;
    if (!take(d, at, where, kObject)) return l;
    l.name = stringAt(d, at + "/name", where);
    if (take(d, at + "/training", where, kObject))
        l.trainingLoss = numberAt(d, at + "/training/loss", where);
    l.judge = judgedAt(d, at + "/judge", where);
    return l;
}

Comparison comparisonOf(const json& d, const std::string& where) {
    Comparison c;
    c.objective = stringAt(d, "/compare/objective", where);
    if (const json* v = take(d, "/compare/regions", where, kString))
        c.regions = v->get<std::string>();
    if (take(d, "/compare/viewing", where, kObject))
        c.viewing = stringAt(d, "/compare/viewing/text", where);
    c.lamp = lightAt(d, "/compare/lamp", where);
    c.paper = lightAt(d, "/compare/paper", where);
    c.optimized = lightAt(d, "/compare/optimized", where);
    if (take(d, "/compare/answer", where, kObject)) {
        ComparedAnswer a;
        a.name = stringAt(d, "/compare/answer/name", where);
        a.merit = stringAt(d, "/compare/answer/merit", where);
        a.optimizedWhy = stringAt(d, "/compare/answer/optimized_why", where);
        a.meritAnswer = numberAt(d, "/compare/answer/merit_answer", where);
        a.meritOptimized = numberAt(d, "/compare/answer/merit_optimized", where);
        a.judge = judgedAt(d, "/compare/answer/judge", where);
        c.answer = std::move(a);
    }
    return c;
}

AnswerCheck answerOf(const json& d, const std::string& where) {
    AnswerCheck a;
    a.light = stringAt(d, "/answer/light", where);
    a.kind = stringAt(d, "/answer/kind", where);
    a.merit = stringAt(d, "/answer/merit", where);
    if (const json* candidates = take(d, "/answer/candidates", where, kArray))
        for (size_t k = 0; k < candidates->size(); ++k) {
            const std::string c = "/answer/candidates/" + std::to_string(k);
            take(d, c, where, kObject);
            AnswerCandidate candidate;
            candidate.name = stringAt(d, c + "/name", where);
            candidate.kind = stringAt(d, c + "/kind", where);
            candidate.merit = numberAt(d, c + "/merit", where);
            if (const json* v = take(d, c + "/eligible", where, kBool))
                candidate.eligible = v->get<bool>();
            candidate.why = stringAt(d, c + "/why", where);
            a.candidates.push_back(std::move(candidate));
        }
    return a;
}

EnvDirection directionAt(const json& d, const std::string& at, const std::string& where) {
    EnvDirection e;
    e.azimuthDeg = numberAt(d, at + "/azimuth_deg", where);
    e.elevationDeg = numberAt(d, at + "/elevation_deg", where);
    return e;
}

EnvDirections directionsOf(const json& d, const std::string& where) {
    const std::string at = "/envmap_directions";
    EnvDirections e;
    if (take(d, at + "/camera", where, kObject)) e.camera = directionAt(d, at + "/camera", where);
    if (take(d, at + "/mirror", where, kObject)) e.mirror = directionAt(d, at + "/mirror", where);
    if (const json* brightest = take(d, at + "/brightest", where, kArray))
        for (size_t k = 0; k < brightest->size(); ++k) {
            const std::string b = at + "/brightest/" + std::to_string(k);
            take(d, b, where, kObject);
            e.brightest.push_back(directionAt(d, b, where));
        }
    return e;
}

}  // namespace

OptimizeSummary optimizeSummaryFromJson(json document, const std::string& where) {
    if (!document.is_object()) throw inputError(where, "not a JSON object");
    OptimizeSummary s;
    const json& d = document;
    if (const json* v = take(d, "/objective", where, kString)) s.objective = v->get<std::string>();
    if (const json* v = take(d, "/lambda", where, kNumber)) s.lambda = v->get<double>();
    if (const json* v = take(d, "/smooth_abs", where, kBool)) s.smoothAbs = v->get<bool>();
    if (const json* v = take(d, "/reg", where, kString)) s.reg = v->get<std::string>();
    if (const json* v = take(d, "/defects_measure", where, kString))
        s.defectsMeasure = v->get<std::string>();
    if (const json* v = take(d, "/defects", where, kString)) s.defects = v->get<std::string>();
    if (const json* v = take(d, "/optimizer", where, kString)) s.optimizer = v->get<std::string>();
    take(d, "/transport", where, kObject);
    if (const json* v = take(d, "/transport/file", where, kString))
        s.transportFile = v->get<std::string>();
    if (const json* v = take(d, "/truth", where, kString)) s.truth = v->get<std::string>();
    // a loss that was not finite is written as null
    if (const json* v = take(d, "/initial_loss", where, kNumber)) s.initialLoss = *v;
    if (const json* v = take(d, "/final_loss", where, kNumber)) s.finalLoss = *v;
    if (const json* v = take(d, "/metrics", where, kObject)) s.metrics = *v;
    if (const json* v = take(d, "/metrics_initial", where, kObject)) s.metricsInitial = *v;
    if (const json* v = take(d, "/compare", where, kObject)) {
        s.compare = *v;
        s.comparison = comparisonOf(d, where);
    }
    if (const json* v = take(d, "/compare/judge_spp", where, kInteger)) s.judgeSpp = v->get<int>();
    if (take(d, "/answer", where, kObject)) s.answer = answerOf(d, where);
    if (take(d, "/envmap_directions", where, kObject)) s.envmapDirections = directionsOf(d, where);
    if (const json* w = take(d, "/warnings", where, kArray))
        for (size_t k = 0; k < w->size(); ++k)
            s.warnings.push_back(stringAt(d, "/warnings/" + std::to_string(k), where));
    if (const json* v = take(d, "/heightmap", where, kObject)) s.heightmap = *v;
    if (const json* v = take(d, "/transport/image", where, kArray)) {
        if (v->size() != 2 || !(*v)[0].is_number_integer() || !(*v)[1].is_number_integer())
            throw inputError(where + " /transport/image",
                             "must be two integers, got " + jsonExcerpt(*v, 40),
                             "write the output again with a current optimize");
        s.image = std::array<int, 2>{(*v)[0].get<int>(), (*v)[1].get<int>()};
    }
    s.heldoutLoss = numberAt(d, "/heldout_loss", where);
    s.heldoutU = numberAt(d, "/heldout_U", where);
    s.document = std::move(document);
    return s;
}

OptimizeSummary readOptimizeSummary(const std::filesystem::path& outDir) {
    const std::filesystem::path file = outDir / kSummary;
    return optimizeSummaryFromJson(
        readJsonInput(file, "the optimize summary",
                      "Check that the file exists (re-run the command that writes it)"),
        file.string());
}

}  // namespace sl::outdir
