#include "io/OptimizeSummary.h"

#include "core/Error.h"
#include "io/InputFile.h"
#include "io/OptimizeOutDir.h"

namespace sl::outdir {

namespace {

using json = nlohmann::json;

/// The value at `pointer`, or nullptr when absent or null.
const json* at(const json& d, const char* pointer) {
    const json::json_pointer p(pointer);
    if (!d.contains(p)) return nullptr;
    const json& v = d.at(p);
    return v.is_null() ? nullptr : &v;
}

[[noreturn]] void wrongType(const std::string& where, const char* pointer, const char* type,
                            const json& v) {
    throw inputError(where + " " + pointer,
                     std::string("must be ") + type + ", got " + jsonExcerpt(v, 40),
                     "write the output again with a current optimize");
}

void take(const json& d, const char* pointer, const std::string& where, std::string& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_string()) wrongType(where, pointer, "a string", *v);
        out = v->get<std::string>();
    }
}

void take(const json& d, const char* pointer, const std::string& where, double& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_number()) wrongType(where, pointer, "a number", *v);
        out = v->get<double>();
    }
}

void take(const json& d, const char* pointer, const std::string& where, bool& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_boolean()) wrongType(where, pointer, "true or false", *v);
        out = v->get<bool>();
    }
}

void take(const json& d, const char* pointer, const std::string& where, std::optional<int>& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_number_integer()) wrongType(where, pointer, "an integer", *v);
        out = v->get<int>();
    }
}

/// A number or null (a loss that was not finite is written as null).
void takeNumber(const json& d, const char* pointer, const std::string& where, json& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_number()) wrongType(where, pointer, "a number or null", *v);
        out = *v;
    }
}

void takeObject(const json& d, const char* pointer, const std::string& where, json& out) {
    if (const json* v = at(d, pointer)) {
        if (!v->is_object()) wrongType(where, pointer, "an object", *v);
        out = *v;
    }
}

}  // namespace

OptimizeSummary optimizeSummaryFromJson(json document, const std::string& where) {
    if (!document.is_object()) throw inputError(where, "not a JSON object");
    OptimizeSummary s;
    take(document, "/objective", where, s.objective);
    take(document, "/lambda", where, s.lambda);
    take(document, "/smooth_abs", where, s.smoothAbs);
    take(document, "/reg", where, s.reg);
    take(document, "/defects_measure", where, s.defectsMeasure);
    take(document, "/optimizer", where, s.optimizer);
    if (const json* t = at(document, "/transport"); t && !t->is_object())
        wrongType(where, "/transport", "an object", *t);
    take(document, "/transport/file", where, s.transportFile);
    take(document, "/truth", where, s.truth);
    takeNumber(document, "/initial_loss", where, s.initialLoss);
    takeNumber(document, "/final_loss", where, s.finalLoss);
    takeObject(document, "/metrics", where, s.metrics);
    takeObject(document, "/metrics_initial", where, s.metricsInitial);
    takeObject(document, "/compare", where, s.compare);
    take(document, "/compare/judge_spp", where, s.judgeSpp);
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
