#include "io/OptimizeSummary.h"

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

/// The value at `pointer`, or nullptr when absent or null; InputError naming `where` and the
/// pointer when it is not of `kind`.
const json* take(const json& d, const char* pointer, const std::string& where, const Kind& kind) {
    const json::json_pointer p(pointer);
    if (!d.contains(p) || d.at(p).is_null()) return nullptr;
    const json& v = d.at(p);
    if (!kind.fits(v))
        throw inputError(where + " " + pointer,
                         std::string("must be ") + kind.name + ", got " + jsonExcerpt(v, 40),
                         "write the output again with a current optimize");
    return &v;
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
    if (const json* v = take(d, "/compare", where, kObject)) s.compare = *v;
    if (const json* v = take(d, "/compare/judge_spp", where, kInteger)) s.judgeSpp = v->get<int>();
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
