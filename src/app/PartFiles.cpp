#include "app/PartFiles.h"

#include <algorithm>
#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/Image.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "io/X3p.h"

namespace sl {

PartFiles writePartFiles(const GeneratedSurface& g, const std::filesystem::path& out,
                         const PartFileOptions& o) {
    const std::string ext = out.extension().string();
    if (ext != ".exr" && ext != ".png" && ext != ".x3p")
        throw inputError(out.string(),
                         "a height map must end in .exr (float32), .png (16-bit) or .x3p (X3P, "
                         "float64 metres)");
    PartFiles f;
    f.heightmap = out;
    Image hm(g.width, g.height, 1);
    auto [mn, mx] = std::minmax_element(g.heights.begin(), g.heights.end());
    f.lo = *mn;
    f.hi = *mx > *mn ? *mx : *mn + 1e-6;
    if (ext == ".exr") {
        hm.data = g.heights;
        writeExr(out, hm);
    } else if (ext == ".x3p") {
        writeX3p(out, g.width, g.height, g.heights, g.pitch);
    } else {
        for (size_t i = 0; i < g.heights.size(); ++i)
            hm.data[i] = static_cast<float>((g.heights[i] - f.lo) / (f.hi - f.lo));
        writePng16(out, hm);
    }
    f.truth = out.parent_path() / (out.stem().string() + "-truth.png");
    f.legend = out.parent_path() / (out.stem().string() + "-truth.json");
    // The legend of the truth labels (judge --truth reads it to name the regions): every label
    // present (synth/SurfaceGenerator.h truthLegend).
    nlohmann::ordered_json legend;
    legend["labels"] = nlohmann::ordered_json::array();
    for (const RegionLabel& l : truthLegend(g.truth))
        legend["labels"].push_back({{"value", l.value}, {"name", l.name}});
    for (const auto& [key, value] : o.legendExtra.items()) legend[key] = value;
    writeMaskPng(f.truth, g.truth, g.width, g.height);
    writeTextAtomically(f.legend, legend.dump(2) + "\n");

    if (!o.scene.empty()) {
        f.scene = o.scene;
        nlohmann::ordered_json hmj;
        hmj["path"] = std::filesystem::relative(std::filesystem::absolute(out),
                                                std::filesystem::absolute(o.scene).parent_path())
                          .generic_string();
        if (ext != ".x3p") hmj["pixel_pitch"] = g.pitch;  // an X3P file carries its pitch
        if (ext == ".png") hmj["height_range"] = {f.lo, f.hi};
        nlohmann::ordered_json j;
        j["description"] = g.description;
        j["heightmap"] = hmj;
        j["material"] = {{"type", "roughconductor"},
                         {"distribution", "ggx"},
                         {"alpha", 0.05},
                         {"material", "Al"}};
        if (o.imageSize > 0) j["camera"] = {{"width", o.imageSize}, {"height", o.imageSize}};
        j["envmap"] = {{"width", 50}, {"height", 25}};
        j["render"] = {{"spp", o.spp}, {"max_depth", o.maxDepth}, {"seed", 0}};
        writeTextAtomically(o.scene, j.dump(2) + "\n");
    }
    return f;
}

}  // namespace sl
