#include "cli/TraceOptions.h"

#include <charconv>
#include <optional>

#include "cli/Common.h"

namespace sl::cli {

namespace {

/// An option that takes a whole number in [lo, hi] (into `value`) or "auto" (sets `isAuto`).
void addNumberOrAuto(CLI::App* c, const std::string& name, std::optional<int>& value, bool& isAuto,
                     int lo, int hi, const std::string& what, const std::string& help) {
    c->add_option_function<std::string>(
         name,
         [&value, &isAuto](const std::string& v) {
             isAuto = v == "auto";
             if (!isAuto) value = std::stoi(v);
         },
         help)
        ->type_name("N|auto")
        ->check([lo, hi, what](const std::string& v) -> std::string {
            if (v == "auto") return {};
            int n = 0;
            const auto [end, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
            if (ec != std::errc{} || end != v.data() + v.size() || n < lo || n > hi)
                return "expected " + what + " " + std::to_string(lo) + ".." + std::to_string(hi) +
                       " or auto, got " + v;
            return {};
        });
}

}  // namespace

void addTraceOptions(CLI::App* c, PrecomputeOptions& p, std::vector<std::string>& overrides,
                     bool noiseAware) {
    addSceneOverrides(c, overrides, true);
    addNumberOrAuto(
        c, "--spp", p.spp, p.autoSpp, 1, 1 << 20, "samples per pixel",
        noiseAware
            ? "Training samples per pixel, or auto (the default): from the scene's render.spp, "
              "raised until the optimized light's train/validation gap is within --tolerance "
              "(measured on an independent validation estimate; every round, the choice and its "
              "seconds are printed). A given N is kept and its gap is warned about"
            : "Samples per pixel (overrides render.spp), or auto: the fewest (a power of two) "
              "whose gradient has a relative noise within --tolerance, measured on a pilot "
              "trace (the choice and why are printed)");
    c->add_option("--tolerance", p.sppTolerance,
                  noiseAware ? "--spp auto: the largest train/validation gap of the optimized "
                               "light (a fraction)"
                             : "--spp auto: the relative noise of the gradient to reach")
        ->check(inRange(1e-6, 0.999999))
        ->capture_default_str();
    addNumberOrAuto(c, "--max-depth", p.maxDepth, p.autoMaxDepth, 1, 64, "a path length",
                    "Mitsuba max_depth (overrides render.max_depth), or auto: the first path "
                    "length whose next bounce adds < 0.1 % of the image under a white light "
                    "(measured first on a lattice of pixels; the choice and why are printed)");
    c->add_option("--seed", p.seed, "Random seed (overrides render.seed)");
    c->add_option("--threads", p.threads, "Worker threads (0: all cores)")->check(inRange(0, 4096));
}

}  // namespace sl::cli
