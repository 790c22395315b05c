#include "app/Judge.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "app/Truth.h"
#include "core/Color.h"
#include "core/Error.h"
#include "objective/UnbiasedObjective.h"
#include "scene/EnvMap.h"
#include "scene/Scene.h"

namespace sl {

TransportSource judgeEstimate(const Scene& scene, const JudgeOptions& o) {
    if (o.spp < 2 || o.spp % 2 != 0)
        throw inputError("judge spp", "must be an even number >= 2, got " + std::to_string(o.spp),
                         "use e.g. 1024");
    PrecomputeOptions p;
    p.spp = o.spp;
    p.seed = o.seed;
    p.maxDepth = o.maxDepth;
    p.rgb = o.rgb;
    p.sampleSets = 2;
    p.threads = o.threads;
    p.label = "judge estimate";
    return transportForScene(scene, p, o.cacheDir);
}

ViewingModel viewingFor(const Scene& scene) {
    try {
        return resolveViewing(scene.desc.viewing, scene.camera.mmPerPixel());
    } catch (const std::invalid_argument& e) {
        throw inputError(
            (scene.desc.file.empty() ? std::string("the scene") : scene.desc.file.string()) +
                ": viewing",
            e.what(), "give positive distances, sizes and white luminance");
    }
}

Judge::Judge(const Scene& scene, const JudgeOptions& options) : options_(options) {
    if (!options_.viewing) options_.viewing = viewingFor(scene);
    owned_ = judgeEstimate(scene, options);
    estimate_ = &*owned_;
    buildObjectives();
    if (!options.truth.empty()) {
        LabelMask m = projectTruth(scene, options.truth, options.threads);
        labels_ = std::move(m.labels);
        legend_ = std::move(m.legend);
    }
}

Judge::Judge(const TransportSource& estimate, const JudgeOptions& options,
             std::vector<uint8_t> labels, std::vector<RegionLabel> legend,
             std::vector<uint8_t> reference)
    : estimate_(&estimate),
      options_(options),
      labels_(std::move(labels)),
      legend_(std::move(legend)),
      reference_(std::move(reference)) {
    const TransportMatrix& t = estimate_->file.matrix;
    if (t.planes != 2)
        throw inputError(estimate_->path.string(), "the judge needs two independent sample sets",
                         "precompute it with " + option("halves"));
    if (!labels_.empty() && labels_.size() != t.rows())
        throw std::invalid_argument("Judge: labels do not match the image size");
    if (!reference_.empty() && reference_.size() != t.rows())
        throw std::invalid_argument("Judge: the reference does not match the image size");
    buildObjectives();
}

Judge::~Judge() = default;

void Judge::buildObjectives() {
    const TransportMatrix& t = estimate_->file.matrix;
    eq2_ = std::make_unique<ImageObjective>(t.width, t.height, partMask(), options_.objective);
    unbiased_ =
        std::make_unique<UnbiasedObjective>(t.width, t.height, partMask(), options_.objective);
}

std::vector<double> Judge::envVector(const EnvMap& env) const {
    const TransportMatrix& t = estimate_->file.matrix;
    if (env.width != t.envWidth || env.height != t.envHeight)
        throw std::invalid_argument("Judge::envVector: env map is not on the judge's grid");
    const size_t n = env.texelCount();
    std::vector<double> e;
    if (env.channels == 1) {
        e.assign(env.texels.begin(), env.texels.end());
    } else if (options_.rgb) {
        e.assign(env.texels.begin(), env.texels.end());
    } else {
        e.resize(n);
        for (size_t i = 0; i < n; ++i)
            e[i] = luminance(double(env.texels[3 * i]), double(env.texels[3 * i + 1]),
                             double(env.texels[3 * i + 2]));
    }
    return e;
}

std::vector<double> Judge::meanImage(std::span<const double> E) const {
    const TransportMatrix& t = estimate_->file.matrix;
    std::vector<double> y(t.rows());
    t.applyLuminance(E, y);
    return y;
}

JudgeScore Judge::score(std::span<const double> E, const std::string& name) const {
    const TransportMatrix& t = estimate_->file.matrix;
    const bool rgb = E.size() == 3 * t.cols();
    JudgeScore s;
    s.name = name;
    if (E.size() != t.cols() && !rgb)
        throw std::invalid_argument("Judge::score: E does not fit the judge's env-map grid");
    // One pass for the mean image (eq. 2) and one for both halves (U and the visibility).
    std::vector<double> y(t.rows()), ya(t.rows()), yb(t.rows());
    t.applyLuminance(E, y);
    t.applyLuminanceHalves(E, ya, yb);
    s.eq2 = eq2_->evaluate(y, E);
    s.unbiased = unbiased_->evaluate(ya, yb, E);
    double sum = 0;
    size_t dark = 0;
    for (double v : E) {
        sum += v;
        dark += v < kDarkTexel;
    }
    s.meanE = E.empty() ? 0 : sum / static_cast<double>(E.size());
    s.sparsity = E.empty() ? 0 : static_cast<double>(dark) / static_cast<double>(E.size());
    double white = 0, lit = 0;
    {
        const std::vector<double> one(E.size(), 1.0);
        std::vector<double> w(t.rows());
        t.applyLuminance(one, w);
        for (size_t p = 0; p < y.size(); ++p)
            if (partMask()[p]) lit += y[p], white += w[p];
    }
    s.brightness = white > 0 ? lit / white : 0.0;
    if (!labels_.empty()) {
        std::optional<JndViewing> viewing;
        const auto partPixels = static_cast<double>(
            std::count_if(partMask().begin(), partMask().end(), [](uint8_t m) { return m != 0; }));
        if (options_.viewing && partPixels > 0)
            viewing = JndViewing{*options_.viewing, white / partPixels};
        s.visibility = defectVisibility(t.width, t.height, ya, yb, partMask(), labels_, legend_,
                                        reference_, viewing ? &*viewing : nullptr);
    }
    return s;
}

namespace {

nlohmann::ordered_json number(double v) {
    return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json parts(const LossParts& p) {
    return {{"loss", number(p.total)},
            {"L_grad", number(p.lGrad)},
            {"L_reg", number(p.lReg)},
            {"G", number(p.G)},
            {"clamped", p.clamped}};
}

}  // namespace

nlohmann::ordered_json viewingJson(const ViewingModel& view) {
    return {{"pixels_per_degree", view.pixelsPerDegree},
            {"white_cd_m2", view.whiteLuminance},
            {"text", view.describe()}};
}

nlohmann::ordered_json toJson(const JudgeScore& s) {
    nlohmann::ordered_json j;
    j["name"] = s.name;
    j["eq2"] = number(s.eq2.total);
    j["unbiased"] = number(s.unbiased.total);
    j["mean_E"] = s.meanE;
    j["sparsity"] = s.sparsity;
    j["brightness"] = number(s.brightness);
    nlohmann::ordered_json v = nlohmann::ordered_json::array();
    for (const RegionVisibility& r : s.visibility)
        v.push_back({{"name", r.label.name},
                     {"value", r.label.value},
                     {"pixels", r.pixels},
                     {"visibility", number(r.visibility)},
                     {"rms_gradient", number(r.rmsGradient)},
                     {"clean_rms_gradient", number(r.cleanRmsGradient)},
                     {"contrast", number(r.contrast)},
                     {"weber", number(r.weber)},
                     {"jnd", number(r.jnd)},
                     {"jnd_frequency_cpd", number(r.jndFrequency)},
                     {"mask_contrast", number(r.maskContrast)},
                     {"luminance_cd_m2", number(r.luminance)}});
    j["visibility"] = v;
    j["eq2_parts"] = parts(s.eq2);
    j["unbiased_parts"] = parts(s.unbiased);
    return j;
}

std::string formatJudgeTable(const std::vector<JudgeScore>& scores) {
    std::vector<std::string> regions;
    for (const JudgeScore& s : scores)
        for (const RegionVisibility& r : s.visibility)
            if (std::find(regions.begin(), regions.end(), r.label.name) == regions.end())
                regions.push_back(r.label.name);
    // JND first where the judge has a viewing model (the ratio beside it).
    const bool jnd = std::any_of(scores.begin(), scores.end(), [](const JudgeScore& s) {
        return std::any_of(s.visibility.begin(), s.visibility.end(),
                           [](const RegionVisibility& r) { return std::isfinite(r.jnd); });
    });
    // The worst label first: by the first light's JND (else visibility), ascending (unmeasured
    // last).
    auto firstVisibility = [&](const std::string& name) {
        if (!scores.empty())
            for (const RegionVisibility& r : scores.front().visibility) {
                const double v = jnd ? r.jnd : r.visibility;
                if (r.label.name == name && std::isfinite(v)) return v;
            }
        return std::numeric_limits<double>::infinity();
    };
    std::stable_sort(regions.begin(), regions.end(),
                     [&](const std::string& a, const std::string& b) {
                         return firstVisibility(a) < firstVisibility(b);
                     });
    size_t nameWidth = 5;
    for (const JudgeScore& s : scores) nameWidth = std::max(nameWidth, s.name.size());
    std::ostringstream out;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%-*s %10s %10s %8s %9s %7s", static_cast<int>(nameWidth),
                  "light", "eq2", "U", "mean E", "dark<1e-3", "bright");
    out << buf;
    for (const std::string& r : regions) {
        if (jnd) {
            std::snprintf(buf, sizeof buf, " %14s", ("JND " + r).substr(0, 14).c_str());
            out << buf;
        }
        std::snprintf(buf, sizeof buf, " %14s %8s", ("vis " + r).substr(0, 14).c_str(), "contrast");
        out << buf;
    }
    out << '\n';
    for (const JudgeScore& s : scores) {
        std::snprintf(buf, sizeof buf, "%-*s %10.4f %10.4f %8.4f %8.1f%% %7.3f",
                      static_cast<int>(nameWidth), s.name.c_str(), s.eq2.total, s.unbiased.total,
                      s.meanE, 100.0 * s.sparsity, s.brightness);
        out << buf;
        for (const std::string& r : regions) {
            const RegionVisibility* v = nullptr;
            for (const RegionVisibility& x : s.visibility)
                if (x.label.name == r) v = &x;
            if (jnd) {
                if (v)
                    std::snprintf(buf, sizeof buf, " %14.2f", v->jnd);
                else
                    std::snprintf(buf, sizeof buf, " %14s", "-");
                out << buf;
            }
            if (v)
                std::snprintf(buf, sizeof buf, " %14.3f %8.4f", v->visibility, v->contrast);
            else
                std::snprintf(buf, sizeof buf, " %14s %8s", "-", "-");
            out << buf;
        }
        out << '\n';
    }
    return out.str();
}

}  // namespace sl
