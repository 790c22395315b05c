#include "app/pipeline/Judge.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "app/pipeline/Truth.h"
#include "core/Color.h"
#include "core/Error.h"
#include "core/Text.h"
#include "core/WildBootstrap.h"
#include "objective/UnbiasedObjective.h"
#include "perception/BandFilters.h"
#include "scene/EnvMap.h"
#include "scene/EnvMapToE.h"
#include "scene/Scene.h"

namespace sl {

TransportSource judgeEstimate(const Scene& scene, const JudgeOptions& o) {
    const int spp = o.spp == 0 ? kJudgeDefaultSpp : o.spp;
    if (spp < 2 || spp % 2 != 0)
        throw inputError("judge spp", "must be an even number >= 2, got " + std::to_string(o.spp),
                         "use e.g. 1024");
    PrecomputeOptions p;
    p.spp = spp;
    p.seed = o.seed;
    p.maxDepth = o.maxDepth;
    p.rgb = o.rgb;
    p.sampleSets = 2;
    p.threads = o.threads;
    p.label = "judge estimate";
    return transportInDoublings(scene, p, kJudgeDoublingBase, o.cacheDir);
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
    return envMapToE(env, options_.rgb ? 3 : 1);
}

std::vector<double> Judge::meanImage(std::span<const double> E) const {
    const TransportMatrix& t = estimate_->file.matrix;
    std::vector<double> y(t.rows());
    t.applyLuminance(E, y);
    return y;
}

const Judge::White& Judge::whiteImages(size_t size, bool halves) const {
    const TransportMatrix& t = estimate_->file.matrix;
    const std::lock_guard<std::mutex> lock(whiteMutex_);
    auto it =
        std::find_if(white_.begin(), white_.end(), [&](const White& w) { return w.size == size; });
    if (it == white_.end()) it = white_.insert(white_.end(), White{size, {}, {}, {}});
    std::vector<double> one;
    if (it->mean.empty() || (halves && it->a.empty())) one.assign(size, 1.0);
    if (it->mean.empty()) {
        it->mean.resize(t.rows());
        t.applyLuminance(one, it->mean);
    }
    if (halves && it->a.empty()) {
        it->a.resize(t.rows());
        it->b.resize(t.rows());
        t.applyLuminanceHalves(one, it->a, it->b);
    }
    return *it;
}

JudgeScore Judge::score(std::span<const double> E, const std::string& name) const {
    const TransportMatrix& t = estimate_->file.matrix;
    const bool rgb = E.size() == 3 * t.cols();
    if (E.size() != t.cols() && !rgb)
        throw std::invalid_argument("Judge::score: E does not fit the judge's env-map grid");
    // One pass for the mean image (eq. 2) and one for both halves (U and the visibility).
    std::vector<double> y(t.rows()), ya(t.rows()), yb(t.rows());
    t.applyLuminance(E, y);
    t.applyLuminanceHalves(E, ya, yb);
    JudgeScore s = scoreImages(E, ya, yb, y, {}, {}, whiteImages(E.size(), false).mean);
    s.name = name;
    return s;
}

JudgeScore Judge::scoreImages(std::span<const double> E, std::span<const double> ya,
                              std::span<const double> yb, std::span<const double> y,
                              std::span<const double> wa, std::span<const double> wb,
                              std::span<const double> w, bool withJnd,
                              const BandFilterBank* bank) const {
    const TransportMatrix& t = estimate_->file.matrix;
    JudgeScore s;
    s.spp = estimate_->file.provenance.spp;
    std::vector<double> mean;
    if (y.empty()) {
        mean.resize(ya.size());
        for (size_t p = 0; p < mean.size(); ++p) mean[p] = 0.5 * (ya[p] + yb[p]);
        y = mean;
    }
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
    for (size_t p = 0; p < y.size(); ++p)
        if (partMask()[p]) lit += y[p], white += w.empty() ? 0.5 * (wa[p] + wb[p]) : w[p];
    s.brightness = white > 0 ? lit / white : 0.0;
    if (!labels_.empty()) {
        std::optional<JndViewing> viewing;
        const auto partPixels = static_cast<double>(
            std::count_if(partMask().begin(), partMask().end(), [](uint8_t m) { return m != 0; }));
        if (withJnd && options_.viewing && partPixels > 0)
            viewing = JndViewing{*options_.viewing, white / partPixels, bank};
        s.visibility = defectVisibility(t.width, t.height, ya, yb, partMask(), labels_, legend_,
                                        reference_, viewing ? &*viewing : nullptr);
    }
    return s;
}

JudgeScore Judge::scoreWithErrors(std::span<const double> E, const std::string& name,
                                  int replicates) const {
    JudgeScore s = score(E, name);
    const TransportMatrix& t = estimate_->file.matrix;
    const size_t n = t.rows();
    // The light's halves and the white furnace's: the same samples made both, so a replicate
    // perturbs them with the same signs (core/WildBootstrap.h).
    std::vector<HalfImages> images(2, HalfImages{std::vector<double>(n), std::vector<double>(n)});
    t.applyLuminanceHalves(E, images[0].a, images[0].b);
    const White& white = whiteImages(E.size(), true);
    images[1].a = white.a;
    images[1].b = white.b;
    const size_t regions = s.visibility.size();
    // The JND figures have errors only where they were formed (a viewing model and regions).
    const bool jnd = std::any_of(s.visibility.begin(), s.visibility.end(),
                                 [](const RegionVisibility& r) { return std::isfinite(r.jnd); });
    // Per replicate: eq2, U, brightness, the combined visibility, the least visible kind's JND,
    // then each region's visibility, contrast and JND.
    constexpr size_t kHead = 5;
    // The band filters depend on the part alone: one bank for every replicate.
    std::optional<BandFilterBank> bank;
    if (jnd) bank.emplace(t.width, t.height, partMask());
    const BandFilterBank* shared = bank ? &*bank : nullptr;
    const std::vector<double> se = wildBootstrapErrors(
        images, options_.seed, replicates,
        [&](std::span<const HalfImages> r) {
            const JudgeScore x =
                scoreImages(E, r[0].a, r[0].b, {}, r[1].a, r[1].b, {}, jnd, shared);
            std::vector<double> v{x.eq2.total, x.unbiased.total, x.brightness,
                                  combinedVisibility(x.visibility), leastVisibleJnd(x.visibility)};
            v.resize(kHead + 3 * regions, std::numeric_limits<double>::quiet_NaN());
            for (size_t k = 0; k < regions && k < x.visibility.size(); ++k) {
                v[kHead + k] = x.visibility[k].visibility;
                v[kHead + regions + k] = x.visibility[k].contrast;
                v[kHead + 2 * regions + k] = x.visibility[k].jnd;
            }
            return v;
        },
        options_.threads);
    JudgeScore::Errors e;
    e.replicates = replicates;
    e.eq2 = se[0];
    // U's by the delta method on the halves' product (objective/UnbiasedObjective.h
    // lossStandardError): the bootstrap's over-states it at a few spp; the bootstrap's where
    // the delta method has none (a clamped G, the image regulariser).
    const double uSe = unbiased_->lossStandardError(images[0].a, images[0].b);
    e.unbiased = std::isfinite(uSe) ? uSe : se[1];
    e.brightness = se[2];
    e.combinedVisibility = se[3];
    e.leastVisibleJnd = se[4];
    for (size_t k = 0; k < regions; ++k) {
        e.visibility.push_back(se[kHead + k]);
        e.contrast.push_back(se[kHead + regions + k]);
        e.jnd.push_back(se[kHead + 2 * regions + k]);
    }
    // Below kJudgeBootstrapFullSpp the bootstrap under-states eq. 2's SE (Judge.h): inflated,
    // and the regions' (not measured there); U's delta-method SE and the brightness's kept.
    if (s.spp > 0 && s.spp < kJudgeBootstrapFullSpp) {
        const double f = kJudgeLowSppInflation;
        e.eq2 *= f;
        e.combinedVisibility *= f;
        e.leastVisibleJnd *= f;
        for (std::vector<double>* v : {&e.visibility, &e.contrast, &e.jnd})
            for (double& x : *v) x *= f;
    }
    s.se = std::move(e);
    return s;
}

namespace {

/// The region of `answer` with the same label as `name` (null if none).
const RegionVisibility* regionNamed(const JudgeScore& answer, const std::string& name) {
    for (const RegionVisibility& r : answer.visibility)
        if (r.label.name == name) return &r;
    return nullptr;
}

}  // namespace

WorstError worstError(const JudgeScore& s, double target, const JudgeScore* answer, double gapShare,
                      double referenceCap) {
    WorstError w;
    if (!s.se) return w;
    const double nan = std::numeric_limits<double>::quiet_NaN();
    auto consider = [&](double value, double se, double floor, const std::string& what,
                        double answerValue) {
        if (!std::isfinite(value)) return;
        const double scale = std::max(std::abs(value), floor);
        // An SE that cannot be formed while the score can: as bad as it gets.
        const double rel = std::isfinite(se) ? se / scale : std::numeric_limits<double>::infinity();
        double allowed = target * scale;
        bool byGap = false;
        if (answer && std::isfinite(answerValue)) {
            const double gap =
                std::min(gapShare * std::abs(value - answerValue), referenceCap * scale);
            if (gap > allowed) allowed = gap, byGap = true;
        }
        const double excess = rel * scale / allowed;
        if (excess > w.excess || w.score.empty()) {
            w.relative = rel;
            w.excess = excess;
            w.byGap = byGap;
            w.score = s.name.empty() ? what : s.name + ": " + what;
        }
    };
    auto of = [&](double JudgeScore::*f) { return answer ? (*answer).*f : nan; };
    consider(s.eq2.total, s.se->eq2, 1e-3, "eq2", answer ? answer->eq2.total : nan);
    consider(s.unbiased.total, s.se->unbiased, 1e-3, "U", answer ? answer->unbiased.total : nan);
    consider(s.brightness, s.se->brightness, 0.05, "brightness", of(&JudgeScore::brightness));
    consider(combinedVisibility(s.visibility), s.se->combinedVisibility, 0.1,
             "visibility (all regions)", answer ? combinedVisibility(answer->visibility) : nan);
    for (size_t k = 0; k < s.visibility.size() && k < s.se->visibility.size(); ++k) {
        const RegionVisibility& r = s.visibility[k];
        const RegionVisibility* a = answer ? regionNamed(*answer, r.label.name) : nullptr;
        consider(r.visibility, s.se->visibility[k], 0.1, "visibility " + r.label.name,
                 a ? a->visibility : nan);
        consider(r.contrast, s.se->contrast[k], 0.01, "contrast " + r.label.name,
                 a ? a->contrast : nan);
    }
    size_t least = 0;
    const double j = leastVisibleJnd(s.visibility, &least);
    if (std::isfinite(j))
        consider(j, s.se->leastVisibleJnd, 1.0, "JND " + s.visibility[least].label.name,
                 answer ? leastVisibleJnd(answer->visibility) : nan);
    return w;
}

WorstError worstRelativeError(const JudgeScore& s) {
    return worstError(s);
}

int nextJudgeSpp(int spp, double worstRelative, int cap, double target) {
    if (!(worstRelative > target) || spp >= cap) return 0;
    const double need =
        std::isfinite(worstRelative)
            ? static_cast<double>(spp) * (worstRelative / target) * (worstRelative / target)
            : static_cast<double>(cap);
    int next = 2 * spp;
    while (next < cap && static_cast<double>(next) < need) next *= 2;
    return std::min(next, cap);
}

std::string JudgedRounds::describe(double target) const {
    if (rounds.empty()) return "not judged";
    const JudgeRound& r = rounds.back();
    const std::string pct = formatNumber(100.0 * target, 2) + " %";
    const std::string share = formatNumber(100.0 * gapShare, 2) + " %";
    auto worstOf = [&](const WorstError& w, bool within) {
        return (within ? "closest to its limit " : "worst ") + formatNumber(100.0 * w.relative, 2) +
               " %" + (w.score.empty() ? std::string() : ", " + w.score) +
               (w.byGap ? " (held to " + share + " of its gap to the answer's)" : std::string());
    };
    std::string spps;
    for (const JudgeRound& x : rounds) spps += (spps.empty() ? "" : " -> ") + std::to_string(x.spp);
    const std::string tail = rounds.size() > 1 ? "; rounds " + spps + " spp" : std::string();
    if (!againstFirst)
        return std::to_string(r.spp) + " spp: " +
               (met ? "every score's standard error <= " + pct + " (" + worstOf(r.worst, true) + ")"
                    : "standard error above " + pct + " at the most " + std::to_string(r.spp) +
                          " spp (" + worstOf(r.worst, false) + ")") +
               tail;
    const bool answerMet = !(r.answer.excess > 1.0), refMet = !(r.references.excess > 1.0);
    std::string out = std::to_string(r.spp) + " spp: the answer's scores' standard errors " +
                      (answerMet ? "<= " + pct + " (" + worstOf(r.answer, true) + ")"
                                 : "above " + pct + " at the most " + std::to_string(r.spp) +
                                       " spp (" + worstOf(r.answer, false) + ")");
    out += refMet ? "; the references' <= " + pct + " or " + share +
                        " of their gap to the answer's (" + worstOf(r.references, true) + ")"
                  : "; a reference's comparison with the answer is not decided at " +
                        std::to_string(r.spp) + " spp (its SE above " + pct + " and " + share +
                        " of its gap to the answer's; " + worstOf(r.references, false) +
                        "; references are traced to at most " + std::to_string(referenceMaxSpp) +
                        " spp)";
    return out + tail;
}

JudgedRounds judgeInRounds(const std::function<const Judge&(int spp)>& judgeAt,
                           const std::vector<std::pair<std::string, std::vector<double>>>& lights,
                           int spp, int cap, double target) {
    JudgeStopRule rule;
    rule.target = target;
    return judgeInRounds(judgeAt, lights, spp, cap, rule);
}

JudgedRounds judgeInRounds(const std::function<const Judge&(int spp)>& judgeAt,
                           const std::vector<std::pair<std::string, std::vector<double>>>& lights,
                           int spp, int cap, const JudgeStopRule& rule) {
    JudgedRounds out;
    out.againstFirst = rule.againstFirst && lights.size() > 1;
    out.gapShare = rule.gapShare;
    out.referenceMaxSpp = out.againstFirst ? std::min(cap, rule.referenceMaxSpp) : cap;
    auto worse = [](WorstError& into, const WorstError& w) {
        if (w.excess > into.excess || into.score.empty()) into = w;
    };
    for (;;) {
        const Judge& judge = judgeAt(spp);
        out.scores.clear();
        JudgeRound round;
        round.spp = spp;
        for (const auto& [name, e] : lights) out.scores.push_back(judge.scoreWithErrors(e, name));
        for (size_t k = 0; k < out.scores.size(); ++k) {
            const bool reference = out.againstFirst && k > 0;
            const WorstError w =
                worstError(out.scores[k], rule.target, reference ? &out.scores[0] : nullptr,
                           rule.gapShare, rule.referenceCap);
            worse(round.worst, w);
            worse(reference ? round.references : round.answer, w);
        }
        out.rounds.push_back(round);
        out.met = !(round.worst.excess > 1.0);
        // The SE falls as 1/sqrt(spp): the excess is the factor to bring below 1; the
        // references' only up to their own cap.
        const int next =
            out.againstFirst
                ? std::max(nextJudgeSpp(spp, round.answer.excess, cap, 1.0),
                           nextJudgeSpp(spp, round.references.excess, out.referenceMaxSpp, 1.0))
                : nextJudgeSpp(spp, round.worst.excess, cap, 1.0);
        if (next == 0) return out;
        const WorstError& why =
            out.againstFirst && nextJudgeSpp(spp, round.answer.excess, cap, 1.0) == next
                ? round.answer
                : (out.againstFirst ? round.references : round.worst);
        spdlog::info(
            "judge: {} spp: standard error {} % ({}{}) > what the rule allows: tracing "
            "again at {} spp",
            spp, formatNumber(100.0 * why.relative, 2), why.score,
            why.byGap ? ", held to " + formatNumber(100.0 * rule.gapShare, 2) +
                            " % of its gap to the answer's"
                      : std::string(),
            next);
        spp = next;
    }
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
    if (s.spp > 0) j["spp"] = s.spp;
    if (s.se) {
        nlohmann::ordered_json e;
        e["eq2"] = number(s.se->eq2);
        e["unbiased"] = number(s.se->unbiased);
        e["brightness"] = number(s.se->brightness);
        e["combined_visibility"] = number(s.se->combinedVisibility);
        e["least_visible_jnd"] = number(s.se->leastVisibleJnd);
        nlohmann::ordered_json per = nlohmann::ordered_json::array();
        for (size_t k = 0; k < s.visibility.size() && k < s.se->visibility.size(); ++k)
            per.push_back({{"name", s.visibility[k].label.name},
                           {"visibility", number(s.se->visibility[k])},
                           {"contrast", number(s.se->contrast[k])},
                           {"jnd", number(k < s.se->jnd.size() ? s.se->jnd[k] : std::nan(""))}});
        e["regions"] = per;
        e["replicates"] = s.se->replicates;
        const WorstError w = worstRelativeError(s);
        e["worst_relative"] = number(w.relative);
        e["worst_score"] = w.score;
        j["se"] = e;
    }
    return j;
}

nlohmann::ordered_json roundsJson(const JudgedRounds& rounds) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (const JudgeRound& r : rounds.rounds)
        a.push_back({{"spp", r.spp},
                     {"worst_relative_se", std::isfinite(r.worst.relative)
                                               ? nlohmann::ordered_json(r.worst.relative)
                                               : nlohmann::ordered_json(nullptr)},
                     {"worst_score", r.worst.score},
                     {"worst_over_allowed", std::isfinite(r.worst.excess)
                                                ? nlohmann::ordered_json(r.worst.excess)
                                                : nlohmann::ordered_json(nullptr)},
                     {"worst_is_reference_gap", r.worst.byGap}});
    return a;
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
    bool errors = false;
    for (const JudgeScore& s : scores) {
        nameWidth = std::max(nameWidth, s.name.size());
        errors |= s.se.has_value();
    }
    // The SE relative to the score, beside it ("±0.4%"), when estimated.
    auto pm = [&](double value, const std::optional<double>& se) -> std::string {
        if (!errors) return {};
        char b[32];
        if (!se || !std::isfinite(value) || value == 0 || !std::isfinite(*se))
            std::snprintf(b, sizeof b, " %6s", "");
        else
            std::snprintf(b, sizeof b, " ±%4.1f%%", 100.0 * *se / std::abs(value));
        return b;
    };
    const std::string pmHead = errors ? std::string(7, ' ') : std::string();
    std::ostringstream out;
    char buf[256];
    std::snprintf(buf, sizeof buf, "%-*s %10s%s %10s%s %8s %9s %7s%s", static_cast<int>(nameWidth),
                  "light", "eq2", pmHead.c_str(), "U", pmHead.c_str(), "mean E", "dark<1e-3",
                  "bright", pmHead.c_str());
    out << buf;
    for (const std::string& r : regions) {
        if (jnd) {
            std::snprintf(buf, sizeof buf, " %14s%s", ("JND " + r).substr(0, 14).c_str(),
                          pmHead.c_str());
            out << buf;
        }
        std::snprintf(buf, sizeof buf, " %14s%s %8s%s", ("vis " + r).substr(0, 14).c_str(),
                      pmHead.c_str(), "contrast", pmHead.c_str());
        out << buf;
    }
    out << '\n';
    for (const JudgeScore& s : scores) {
        auto se = [&](double JudgeScore::Errors::*f) {
            return s.se ? std::optional<double>((*s.se).*f) : std::nullopt;
        };
        std::snprintf(buf, sizeof buf, "%-*s %10.4f%s %10.4f%s %8.4f %8.1f%% %7.3f%s",
                      static_cast<int>(nameWidth), s.name.c_str(), s.eq2.total,
                      pm(s.eq2.total, se(&JudgeScore::Errors::eq2)).c_str(), s.unbiased.total,
                      pm(s.unbiased.total, se(&JudgeScore::Errors::unbiased)).c_str(), s.meanE,
                      100.0 * s.sparsity, s.brightness,
                      pm(s.brightness, se(&JudgeScore::Errors::brightness)).c_str());
        out << buf;
        for (const std::string& r : regions) {
            const RegionVisibility* v = nullptr;
            size_t k = 0;
            for (size_t i = 0; i < s.visibility.size(); ++i)
                if (s.visibility[i].label.name == r) v = &s.visibility[i], k = i;
            const bool hasSe = s.se && k < s.se->visibility.size();
            if (jnd) {
                const bool hasJndSe = s.se && k < s.se->jnd.size();
                if (v)
                    std::snprintf(
                        buf, sizeof buf, " %14.2f%s", v->jnd,
                        pm(v->jnd, hasJndSe ? std::optional(s.se->jnd[k]) : std::nullopt).c_str());
                else
                    std::snprintf(buf, sizeof buf, " %14s%s", "-", pmHead.c_str());
                out << buf;
            }
            if (v)
                std::snprintf(
                    buf, sizeof buf, " %14.3f%s %8.4f%s", v->visibility,
                    pm(v->visibility, hasSe ? std::optional(s.se->visibility[k]) : std::nullopt)
                        .c_str(),
                    v->contrast,
                    pm(v->contrast, hasSe ? std::optional(s.se->contrast[k]) : std::nullopt)
                        .c_str());
            else
                std::snprintf(buf, sizeof buf, " %14s%s %8s%s", "-", pmHead.c_str(), "-",
                              pmHead.c_str());
            out << buf;
        }
        out << '\n';
    }
    return out.str();
}

}  // namespace sl
