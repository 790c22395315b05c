#include "app/pipeline/TrainingNoise.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/Text.h"

namespace sl {

PrecomputeOptions validationOptions(const PrecomputeOptions& training, uint64_t trainingSeed,
                                    int spp) {
    PrecomputeOptions o = training;
    if (spp > 0) o.spp = spp;
    o.seed = trainingSeed + kValidationSeedOffset;
    o.sampleSets = 2;
    o.label = "validation estimate";
    return o;
}

TransportSource validationEstimate(const Scene& scene, const PrecomputeOptions& training,
                                   uint64_t trainingSeed, const std::filesystem::path& cacheDir,
                                   int spp) {
    return transportForScene(scene, validationOptions(training, trainingSeed, spp), cacheDir);
}

int sppCapForImage(int spp, size_t pixels) {
    int scale = 1;
    while (scale < kMaxSppCapScale && pixels > 0 && pixels * 2 * scale <= kSppCapPixels) scale *= 2;
    return spp * scale;
}

TrainingNoiseOptions TrainingNoiseOptions::forImage(size_t pixels, bool keepMaxSpp) const {
    TrainingNoiseOptions o = *this;
    if (!keepMaxSpp) o.maxSpp = sppCapForImage(maxSpp, pixels);
    o.maxValidationSpp = sppCapForImage(maxValidationSpp, pixels);
    return o;
}

int validationPilotSpp(int trainingSpp) {
    const int quarter = (trainingSpp / 4) & ~1;
    return std::min(trainingSpp, std::max(kValidationPilotSpp, quarter));
}

namespace {
/// The largest power of two ≤ kDefectSppScale whose extra samples on `pixels` fit in `budget`
/// pixels' worth.
int factorWithin(size_t pixels, double budget) {
    int f = kDefectSppScale;
    while (f > 1 && static_cast<double>(pixels) * (f - 1) > budget) f /= 2;
    return pixels == 0 ? 1 : f;
}
}  // namespace

int defectSppFactor(size_t defectPixels, size_t partPixels) {
    return factorWithin(defectPixels, kDefectSppBudget * static_cast<double>(partPixels));
}

std::array<int, 256> defectSppFactors(const std::array<size_t, 256>& labelPixels,
                                      size_t partPixels) {
    std::array<int, 256> factors;
    factors.fill(1);
    double budget = kDefectSppBudget * static_cast<double>(partPixels);
    for (const size_t v : labelsBySize(labelPixels)) {
        const size_t n = labelPixels[v];
        const int f = factorWithin(n, budget);
        factors[v] = f;
        budget -= static_cast<double>(n) * (f - 1);
    }
    return factors;
}

std::vector<size_t> labelsBySize(const std::array<size_t, 256>& labelPixels) {
    std::vector<size_t> labels;
    for (size_t v = 1; v < 256; ++v)
        if (labelPixels[v] > 0) labels.push_back(v);
    std::stable_sort(labels.begin(), labels.end(),
                     [&](size_t a, size_t b) { return labelPixels[a] < labelPixels[b]; });
    return labels;
}

std::vector<uint8_t> defectSppScale(const std::vector<uint8_t>& defects,
                                    const std::array<int, 256>& factors) {
    if (std::all_of(factors.begin() + 1, factors.end(), [](int f) { return f <= 1; })) return {};
    std::vector<uint8_t> s(defects.size(), 1);
    for (size_t p = 0; p < s.size(); ++p)
        if (defects[p]) s[p] = static_cast<uint8_t>(std::max(1, factors[defects[p]]));
    return s;
}

std::vector<uint8_t> defectSppScale(const std::vector<uint8_t>& defects, int factor) {
    std::array<int, 256> factors;
    factors.fill(factor);
    return defectSppScale(defects, factors);
}

bool figureHigherIsBetter(ObjectiveKind kind) {
    switch (kind) {
        case ObjectiveKind::Paper:
        case ObjectiveKind::Unbiased:
            return false;
        case ObjectiveKind::Defects:
            return true;
    }
    return false;
}

double trainingFigure(ObjectiveKind kind, const LossParts& parts) {
    switch (kind) {
        case ObjectiveKind::Paper:
        case ObjectiveKind::Unbiased:
            return parts.total;
        case ObjectiveKind::Defects:
            // L_vis = ψ(g(R)) − φ(g(D)) = −2·log(visibility) with the objective's own floors: a
            // light whose reference energy the estimate's noise pushed below the floor has an
            // enormous visibility on that estimate, and this says so.
            return std::exp(-0.5 * parts.lGrad);
    }
    return parts.total;
}

double trainingGap(ObjectiveKind kind, double training, double validation) {
    const double better =
        figureHigherIsBetter(kind) ? training - validation : validation - training;
    if (validation == 0) return better > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    return better / std::abs(validation);
}

const char* gapVerdictName(GapVerdict v) {
    switch (v) {
        case GapVerdict::Within:
            return "within";
        case GapVerdict::OverFit:
            return "over-fit";
        case GapVerdict::ValidationNoise:
            return "validation noise";
        case GapVerdict::Above:
            return "above";
    }
    return "within";
}

GapVerdict gapVerdict(double gap, double se, double maxGap, bool validationAtMost) {
    if (std::isnan(se)) return validationAtMost ? GapVerdict::OverFit : GapVerdict::ValidationNoise;
    if (gap - kGapSigmas * se > maxGap) return GapVerdict::OverFit;
    if (se > maxGap) return GapVerdict::ValidationNoise;
    if (gap > maxGap) return GapVerdict::Above;
    return GapVerdict::Within;
}

double trainingGapError(ObjectiveKind kind, const TransportLoss& onValidation,
                        std::span<const double> E, uint64_t seed, int replicates,
                        const UnbiasedObjective* unbiased) {
    const std::vector<HalfImages> images{onValidation.halfImages(E)};
    const LossParts parts = onValidation.evaluateImages(images.front(), E);
    const double figure = trainingFigure(kind, parts);
    if (parts.clamped || !(std::abs(figure) > 0)) return std::numeric_limits<double>::quiet_NaN();
    if (unbiased && kind == ObjectiveKind::Unbiased) {
        const double se = unbiased->lossStandardError(images[0].a, images[0].b);
        if (std::isfinite(se)) return se / std::abs(figure);
    }
    const double se =
        wildBootstrapErrors(images, seed, replicates, [&](std::span<const HalfImages> r) {
            return std::vector<double>{trainingFigure(kind, onValidation.evaluateImages(r[0], E))};
        }).front();
    return se / std::abs(figure);
}

bool validationSppFree(ObjectiveKind kind) {
    return kind != ObjectiveKind::Paper;
}

std::optional<int> nextValidationSpp(int spp, double se, const TrainingNoiseOptions& o) {
    const int next =
        nextJudgeSpp(spp, std::isnan(se) ? std::numeric_limits<double>::infinity() : se,
                     o.maxValidationSpp, o.maxGap);
    if (next <= spp) return std::nullopt;
    return next;
}

GapDecision decideAfterRound(const TrainingNoiseRound& r, ObjectiveKind kind,
                             const TrainingNoiseOptions& o, int envWidth, int envHeight) {
    GapDecision d;
    // V's spp may rise alone where its figure does not depend on it; eq. 2's V keeps T's.
    const bool freeV = validationSppFree(kind);
    const bool vAtMost =
        freeV ? !o.adapt || r.validationSpp >= o.maxValidationSpp : !o.adapt || r.spp >= o.maxSpp;
    d.verdict = gapVerdict(r.gap, r.gapError, o.maxGap, vAtMost);
    const double se = std::isnan(r.gapError) ? std::numeric_limits<double>::infinity() : r.gapError;
    switch (d.verdict) {
        case GapVerdict::Within:
            return d;
        case GapVerdict::ValidationNoise:
            if (o.adapt && freeV) {
                d.nextValidation = nextValidationSpp(r.validationSpp, r.gapError, o).value_or(0);
            } else if (o.adapt) {  // eq. 2's V keeps T's spp: both rise to V's target
                const int next = nextJudgeSpp(r.spp, se, o.maxSpp, o.maxGap);
                d.nextTraining = next > r.spp ? next : 0;
            }
            d.unresolved = d.nextValidation == 0 && d.nextTraining == 0;
            return d;
        case GapVerdict::Above:
            // A given spp keeps its light here (it is only warned about).
            if (!o.adapt) {
                d.unresolved = true;
                return d;
            }
            if (freeV && se > kAboveErrorShare * o.maxGap) {
                const int next = nextJudgeSpp(r.validationSpp, se, o.maxValidationSpp,
                                              kAboveErrorShare * o.maxGap);
                if (next > r.validationSpp) {
                    d.nextValidation = next;
                    return d;
                }
            }
            break;
        case GapVerdict::OverFit:
            break;
    }
    // Over-fit, or above with V resolved: more T, then a coarser light (step 5).
    if (o.adapt) d.nextTraining = nextTrainingSpp(r.spp, r.gap, o).value_or(0);
    if (d.nextTraining == 0 && o.adaptGrid) d.coarser = nextLightGrid(r.grid, envWidth, envHeight);
    d.unresolved = d.verdict == GapVerdict::Above && d.nextTraining == 0 && !d.coarser;
    return d;
}

std::string GapDecision::describe() const {
    if (nextValidation > 0) return "V at " + std::to_string(nextValidation) + " spp";
    if (nextTraining > 0) return "T at " + std::to_string(nextTraining) + " spp";
    if (coarser) return "a coarser light, " + coarser->name();
    if (verdict == GapVerdict::Within) return "kept";
    if (unresolved) return "kept: not resolved at this cost";
    return "kept: over-fit at the limits";
}

std::optional<int> nextTrainingSpp(int spp, double gap, const TrainingNoiseOptions& o) {
    if (spp >= o.maxSpp) return std::nullopt;
    // The noise's share of the gap falls as 1/spp: aim at half the tolerance.
    const double wanted = std::isfinite(gap) ? spp * gap / (0.5 * o.maxGap) : double(o.maxSpp);
    int n = 2 * spp;
    while (n < o.maxSpp && n < wanted && n < kMaxSppGrowth * spp) n *= 2;
    return std::min(n, o.maxSpp);
}

std::optional<LightGrid> nextLightGrid(const LightGrid& grid, int envWidth, int envHeight) {
    const int w = grid.perTexel() ? envWidth : grid.width;
    const int h = grid.perTexel() ? envHeight : grid.height;
    const int nw = std::max(1, static_cast<int>(std::lround(w / std::sqrt(2.0))));
    const int nh = std::max(2, static_cast<int>(std::lround(h / std::sqrt(2.0))));
    if (nw * nh < kCoarsestLightNodes || (nw == w && nh == h)) return std::nullopt;
    return LightGrid{nw, nh};
}

std::string describeTrainingNoise(const TrainingNoiseSummary& s) {
    if (s.rounds.empty()) return "not measured";
    auto pct = [](double x) { return formatNumber(100.0 * x, 3) + " %"; };
    std::string out;
    for (size_t k = 0; k < s.rounds.size(); ++k) {
        const TrainingNoiseRound& r = s.rounds[k];
        out += (k ? "; " : "") + std::to_string(r.spp) + " spp" +
               (r.grid.perTexel() ? std::string() : ", " + r.grid.name()) +
               (r.validationSpp > 0 && r.validationSpp != r.spp
                    ? ", V " + std::to_string(r.validationSpp) + " spp"
                    : std::string()) +
               ": train/validation gap " + pct(r.gap) +
               (std::isfinite(r.gapError) ? " ± " + pct(r.gapError) : std::string(" ± ?"));
    }
    const std::string on = s.grid().perTexel() ? std::string() : " on " + s.grid().name();
    const std::string tol = pct(s.maxGap);
    const std::string noise = "within " + tol;
    const std::string vAt =
        "V at " + std::to_string(std::max(s.rounds.back().validationSpp, s.spp())) + " spp";
    const std::string unresolved =
        s.rounds.back().verdict == GapVerdict::Above
            ? ": ABOVE " + tol + " by less than " + vAt +
                  "'s noise explains, so the gap is not resolved at this cost (the light is kept)"
            : ": within what V's noise explains, but " + vAt + " cannot resolve " + tol +
                  ", so the gap is not resolved at this cost (the light is "
                  "kept, V's noise not chased)";
    if (!s.adapted)
        out += s.met          ? " (the given spp" + on + "; " + noise + ")"
               : s.unresolved ? " (the given spp" + on + ")" + unresolved
                              : " (the given spp" + on + ": ABOVE " + tol +
                                    ", so the light partly fits the training estimate's noise; "
                                    "leave spp to the rule or raise it)";
    else if (s.met)
        out += " -> " + std::to_string(s.spp()) + " spp" + on + " (" + noise + ")";
    else if (s.unresolved)
        out += " -> " + std::to_string(s.spp()) + " spp" + on + unresolved;
    else
        out +=
            " -> " + std::to_string(s.spp()) + " spp" + on + ", the most spp the rule traces" +
            (s.gridAdapted ? " and the coarsest light it searches" : " on the light's given grid") +
            ", still above " + tol + ": no light is trusted on its training estimate alone";
    return out;
}

}  // namespace sl
