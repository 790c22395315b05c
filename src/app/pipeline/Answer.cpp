#include "app/pipeline/Answer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/Text.h"
#include "objective/DefectVisibility.h"

namespace sl {

AnswerMerit answerMerit(const JudgeScore& s, bool inJnd) {
    const bool regions = std::any_of(s.visibility.begin(), s.visibility.end(),
                                     [](const RegionVisibility& r) { return r.pixels > 0; });
    const double v = combinedVisibility(s.visibility);
    size_t least = 0;
    const double j = leastVisibleJnd(s.visibility, &least);
    const bool jnd = regions && inJnd;
    AnswerMerit m{jnd ? j : regions ? v : s.unbiased.total,          regions,
                  jnd ? "JND" : regions ? "defect visibility" : "U", v,
                  std::numeric_limits<double>::quiet_NaN(),          std::string()};
    if (jnd && std::isfinite(j)) {
        m.pooled = combinedJnd(s.visibility);
        m.leastVisible = s.visibility[least].label.name;
    }
    return m;
}

bool betterMerit(const AnswerMerit& a, const AnswerMerit& b) {
    if (!std::isfinite(a.value)) return false;
    if (!std::isfinite(b.value)) return true;
    if (a.value == b.value) return a.pooled > b.pooled;
    return a.higherIsBetter ? a.value > b.value : a.value < b.value;
}

const char* candidateKindName(CandidateKind kind) {
    switch (kind) {
        case CandidateKind::Reference:
            return "reference";
        case CandidateKind::Finer:
            return "finer";
        case CandidateKind::Optimized:
        case CandidateKind::Start:
            break;
    }
    return "optimized";
}

AnswerChoice chooseAnswer(const Judge& validation, std::vector<AnswerCandidate> candidates,
                          const AnswerOptions& options) {
    const auto t0 = std::chrono::steady_clock::now();
    AnswerChoice c;
    bool anyOptimized = false, anyEligible = false;
    for (AnswerCandidate& cand : candidates) {
        ScoredCandidate s;
        s.score = validation.score(cand.e, cand.name);
        s.merit = answerMerit(s.score, validation.options().viewing.has_value());
        if (!(s.score.brightness >= options.minBrightness)) {
            s.eligible = false;
            s.why = "too dark: brightness " + formatNumber(s.score.brightness, 3) +
                    " of the white furnace, below " + formatNumber(options.minBrightness, 3);
        } else if (s.merit.what == "defect visibility") {
            // A ratio of two gradients a light barely makes is noise over noise: the defects
            // must also show against the image's brightness. (JND needs no such floor: it is
            // the defects' contrast over the eye's threshold at the image's luminance, so a
            // light that barely shows them has a JND near 0 by itself.)
            const double contrast = combinedContrast(s.score.visibility);
            if (!(contrast >= options.minContrast)) {
                s.eligible = false;
                s.why = "the defects barely show: their gradient is " + formatNumber(contrast, 3) +
                        " of the image's brightness, below " + formatNumber(options.minContrast, 3);
            }
        }
        anyOptimized |= cand.kind != CandidateKind::Reference;
        anyEligible |= s.eligible;
        s.candidate = std::move(cand);
        c.scored.push_back(std::move(s));
    }
    c.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    bool jndFloored = false;  // the lamp shows the defects less than kGainFloorJnd
    if (!options.gainOver.empty()) {
        const auto anchor = std::find_if(
            c.scored.begin(), c.scored.end(),
            [&](const ScoredCandidate& s) { return s.candidate.name == options.gainOver; });
        if (anchor != c.scored.end() && anchor->merit.what == "JND") {
            // The JND gain counted from the threshold of seeing, as the objective's anchor
            // (objective/BothMeasuresObjective.h); a lamp whose ratio cannot be formed leaves
            // the JND's gain alone.
            jndFloored = !(anchor->merit.value >= options.gainFloorJnd);
            const double j0 = jndFloored ? options.gainFloorJnd : anchor->merit.value;
            const double v0 = anchor->merit.visibility;
            const bool ratioGain = std::isfinite(v0) && v0 > 0;
            for (ScoredCandidate& s : c.scored) {
                s.merit.jnd = s.merit.value;
                s.merit.value = ratioGain ? std::min(s.merit.jnd / j0, s.merit.visibility / v0)
                                          : s.merit.jnd / j0;
                s.merit.what = "gain over " + options.gainOver;
            }
        }
    }
    if (!anyOptimized) throw std::invalid_argument("chooseAnswer: no optimized candidate");
    // A finer light competes only when no trusted optimized light passes the checks.
    bool trustedEligible = false;
    for (const ScoredCandidate& s : c.scored)
        trustedEligible |= s.eligible && (s.candidate.kind == CandidateKind::Optimized ||
                                          s.candidate.kind == CandidateKind::Start);
    if (trustedEligible) {
        anyEligible = false;
        for (ScoredCandidate& s : c.scored) {
            if (s.candidate.kind == CandidateKind::Finer && s.eligible) {
                s.eligible = false;
                s.why =
                    "its training figure fits the estimate's noise, and a trusted optimized "
                    "light passes the checks";
            }
            anyEligible |= s.eligible;
        }
    }
    // When every candidate is too dark, the brightest-merit one is still the answer (said so).
    bool haveBest = false, haveOpt = false;
    for (size_t k = 0; k < c.scored.size(); ++k) {
        const ScoredCandidate& s = c.scored[k];
        if ((s.candidate.kind == CandidateKind::Optimized ||
             s.candidate.kind == CandidateKind::Start) &&
            (!haveOpt || betterMerit(s.merit, c.scored[c.optimized].merit))) {
            c.optimized = k;
            haveOpt = true;
        }
        if ((s.eligible || !anyEligible) &&
            (!haveBest || betterMerit(s.merit, c.scored[c.chosen].merit))) {
            c.chosen = k;
            haveBest = true;
        }
    }
    const ScoredCandidate& a = c.answer();
    const ScoredCandidate& o = c.scored[c.optimized];
    const bool jnd = a.merit.what == "JND";  // which kind shows least, pooled and ratio beside
    const bool gain = std::isfinite(a.merit.jnd);
    std::string on = " on the validation estimate (" +
                     (gain ? "the smaller of the JND's and the visibility ratio's gains over " +
                                 options.gainOver + " "
                           : a.merit.what + (jnd ? " of the least visible kind " : " ")) +
                     formatNumber(a.merit.value, 4) +
                     (jnd ? " (" + a.merit.leastVisible + ")" : "") + " vs the optimized light's " +
                     formatNumber(o.merit.value, 4) +
                     (jnd ? " (" + o.merit.leastVisible + ")" : "");
    if (gain)
        on += "; JND of the least visible kind " + formatNumber(a.merit.jnd, 4) + " vs " +
              formatNumber(o.merit.jnd, 4) + "; visibility ratio " +
              formatNumber(a.merit.visibility, 4) + " vs " + formatNumber(o.merit.visibility, 4) +
              (jndFloored ? "; " + options.gainOver + " shows the defects less than " +
                                formatNumber(options.gainFloorJnd, 2) +
                                " JND, so the JND's gain is counted from there"
                          : std::string());
    if (jnd)
        on += "; all kinds pooled " + formatNumber(a.merit.pooled, 4) + " vs " +
              formatNumber(o.merit.pooled, 4) + "; visibility ratio " +
              formatNumber(a.merit.visibility, 4) + " vs " + formatNumber(o.merit.visibility, 4);
    on += ")";
    if (!anyEligible)
        c.reason = "no light passes the checks (brightness at least " +
                   formatNumber(options.minBrightness, 3) +
                   " of white, defects showing against it); " + a.candidate.name +
                   " is the best of them" + on;
    else if (a.candidate.kind == CandidateKind::Finer)
        c.reason = "the optimized light does not pass the checks on the validation estimate (" +
                   o.why + "); " + a.candidate.name +
                   ", searched before it on a finer grid (its training figure fits the noise), "
                   "is the best light that does" +
                   on;
    else if (c.referenceWon() && !o.eligible)
        c.reason = "the optimized light does not pass the checks on the validation estimate (" +
                   o.why + "); the reference light " + a.candidate.name +
                   " is the best light that does" + on;
    else if (c.referenceWon())
        c.reason = "the reference light " + a.candidate.name +
                   " shows the defects better than the optimized light" + on;
    else
        c.reason = "the optimized light (" + a.candidate.name + ") is the best of " +
                   std::to_string(c.scored.size()) + " candidates" + on;
    return c;
}

bool answerDecided(const AnswerChoice& c, double relativeSe) {
    if (!std::isfinite(relativeSe)) return false;
    const ScoredCandidate& a = c.answer();
    const bool reference = a.candidate.kind == CandidateKind::Reference;
    const ScoredCandidate* rival = nullptr;
    for (const ScoredCandidate& s : c.scored)
        if (s.eligible && (s.candidate.kind == CandidateKind::Reference) != reference &&
            std::isfinite(s.merit.value) && (!rival || betterMerit(s.merit, rival->merit)))
            rival = &s;
    if (!rival || !std::isfinite(a.merit.value)) return true;
    const double scale = std::max(std::abs(a.merit.value), std::abs(rival->merit.value));
    return std::abs(a.merit.value - rival->merit.value) >
           kAnswerMarginSigmas * std::sqrt(2.0) * relativeSe * scale;
}

nlohmann::ordered_json answerJson(const AnswerChoice& a) {
    nlohmann::ordered_json scored = nlohmann::ordered_json::array();
    for (const ScoredCandidate& c : a.scored)
        scored.push_back({{"name", c.candidate.name},
                          {"kind", candidateKindName(c.candidate.kind)},
                          {"merit", c.merit.value},
                          {"visibility", c.merit.visibility},
                          {"jnd_pooled", c.merit.pooled},
                          {"least_visible", c.merit.leastVisible},
                          {"brightness", c.score.brightness},
                          {"eligible", c.eligible},
                          {"why", c.why}});
    nlohmann::ordered_json j = {
        {"light", a.answer().candidate.name},
        {"kind", candidateKindName(a.answer().candidate.kind)},
        {"merit", a.answer().merit.what},
        {"merit_of", a.answer().merit.what == "JND" ? "the least visible defect kind"
                     : a.answer().merit.what == "U" ? "the image"
                                                    : "all defect regions"},
        {"higher_is_better", a.answer().merit.higherIsBetter},
        {"reason", a.reason},
        {"seconds", a.seconds},
        {"on", "the validation estimate (independent of training and the judge)"},
        {"candidates", scored}};
    if (a.validationSpp > 0) j["validation_spp"] = a.validationSpp;
    return j;
}

}  // namespace sl
