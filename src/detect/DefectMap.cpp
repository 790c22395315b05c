#include "detect/DefectMap.h"

#include <cmath>
#include <limits>

#include "core/Error.h"
#include "core/Registry.h"
#include "core/Text.h"

namespace sl {

namespace {

constexpr DefectMethodRow kMethods[] = {
    {DefectMethod::Auto, "auto",
     "a simulator's part: remove the periodic tool-path texture (spectral notch) and a robust "
     "local level, mark what stands out (levels, edges, texture-change regions); a measurement "
     "(an instrument's file, or heightmap.measured): selfsim"},
    {DefectMethod::Lay, "lay",
     "measured textures: the median along the texture's own lay is its background; mark regions "
     "far above the residual's robust sigma and the texture's RMS, none along the border"},
    {DefectMethod::SelfSim, "selfsim",
     "what the texture does not repeat: each sample's background is the median of its copies at "
     "the texture's own offsets; mark what an a-contrario test finds in the residual"},
    {DefectMethod::Paper, "paper",
     "the paper's scratch map: patches whose moving-average-detrended range is large"},
};

}  // namespace

std::span<const DefectMethodRow> defectMethodTable() {
    return kMethods;
}

DefectMethod parseDefectMethod(std::string_view name, const std::string& where) {
    return parseRegistryName(defectMethodTable(), name, where).value;
}

const char* defectMethodName(DefectMethod method) {
    return registryRow(defectMethodTable(), method).name;
}

size_t DefectMap::markedCount() const {
    size_t n = 0;
    for (uint8_t v : map) n += v != 0;
    return n;
}

double DefectMap::markedFraction() const {
    return map.empty() ? 0.0 : static_cast<double>(markedCount()) / static_cast<double>(map.size());
}

size_t DefectMap::unjudgedCount() const {
    size_t n = 0;
    for (uint8_t v : unjudged) n += v == kUnjudgedRegion;
    return n;
}

std::string DefectMap::whyNothingMarked() const {
    const size_t dropped = selfsimDroppedTexture + selfsimDroppedShallow;
    if (method != DefectMethod::SelfSim || dropped == 0 || markedCount() > 0) return {};
    std::string why;
    why.append(std::to_string(dropped))
        .append(dropped == 1 ? " region" : " regions")
        .append(" stood out of the residual's noise (above ")
        .append(formatNumber(selfsimThreshold, 3))
        .append(" robust sigmas) but none above what the texture's own features reach:");
    if (selfsimDroppedTexture > 0)
        why.append(" ")
            .append(std::to_string(selfsimDroppedTexture))
            .append(" no higher than the texture's own tail (")
            .append(formatNumber(selfsimTextureThreshold, 3))
            .append(" robust sigmas)")
            .append(selfsimLineThreshold > 0.0 ? " and holding no line above its tail of lines"
                                               : "");
    if (selfsimDroppedTexture > 0 && selfsimDroppedShallow > 0) why.append(",");
    if (selfsimDroppedShallow > 0)
        why.append(" ")
            .append(std::to_string(selfsimDroppedShallow))
            .append(" shallower than its RMS (")
            .append(formatNumber(selfsimTextureRms, 4))
            .append(" height units)");
    why.append(
        ". A defect that stands no higher than the texture's own features, and is not a long "
        "even line, is not told from them: on textures the map was not tuned on (a rubber's "
        "pores, a coin's relief) it misses dents and pits a person sees");
    return why;
}

DefectMethod methodInForce(const DefectMapOptions& options) {
    return options.method == DefectMethod::Auto && options.measured ? DefectMethod::SelfSim
                                                                    : options.method;
}

DefectScore scoreDefectMap(std::span<const uint8_t> map, std::span<const uint8_t> labels,
                           std::span<const RegionLabel> legend,
                           std::span<const uint8_t> negatives) {
    if (map.size() != labels.size())
        throw inputError("defect score",
                         "the map has " + std::to_string(map.size()) + " samples, the truth " +
                             std::to_string(labels.size()),
                         "Score a map against the truth of the same height map");
    bool negative[256] = {};
    for (uint8_t v : negatives) negative[v] = true;
    size_t count[256] = {}, hit[256] = {};
    size_t marked = 0;
    for (size_t k = 0; k < map.size(); ++k) {
        ++count[labels[k]];
        if (map[k]) {
            ++hit[labels[k]];
            ++marked;
        }
    }
    auto ratio = [](size_t a, size_t b) {
        return b ? static_cast<double>(a) / static_cast<double>(b)
                 : std::numeric_limits<double>::quiet_NaN();
    };
    auto f1 = [](double p, double r) {
        return std::isfinite(p) && std::isfinite(r) && p + r > 0 ? 2 * p * r / (p + r) : 0.0;
    };
    size_t negMarked = hit[0];
    for (int v = 1; v < 256; ++v)
        if (negative[v]) negMarked += hit[v];
    DefectScore s;
    s.marked = marked;
    s.samples = map.size();
    DefectScoreRow& all = s.overall;
    all.name = "all";
    for (int v = 1; v < 256; ++v)
        if (!negative[v]) {
            all.truth += count[v];
            all.hits += hit[v];
        }
    all.marked = marked;
    all.precision = ratio(all.hits, all.marked);
    all.recall = ratio(all.hits, all.truth);
    all.f1 = f1(all.precision, all.recall);
    for (const RegionLabel& l : legend) {
        DefectScoreRow row;
        row.value = l.value;
        row.name = l.name;
        row.truth = count[l.value];
        row.hits = hit[l.value];
        row.marked = row.hits + (negative[l.value] ? negMarked - hit[l.value] : negMarked);
        row.precision = ratio(row.hits, row.marked);
        row.recall = ratio(row.hits, row.truth);
        row.f1 = f1(row.precision, row.recall);
        s.kinds.push_back(row);
    }
    return s;
}

}  // namespace sl
