#include "app/jobs/PartFiles.h"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>

#include "core/Error.h"
#include "core/Image.h"
#include "core/Interrupt.h"
#include "io/AtomicFile.h"
#include "io/ImageIO.h"
#include "io/InputFile.h"
#include "io/X3p.h"
#include "scene/Scene.h"

namespace sl {

PartFiles checkPartFiles(const std::filesystem::path& out, const PartFileOptions& o) {
    const std::string ext = out.extension().string();
    if (ext != ".exr" && ext != ".png" && ext != ".x3p")
        throw inputError(out.string(),
                         "a height map must end in .exr (float32), .png (16-bit) or .x3p (X3P, "
                         "float64 metres)");
    PartFiles f;
    f.heightmap = out;
    f.truth = out.parent_path() / (out.stem().string() + "-truth.png");
    f.legend = out.parent_path() / (out.stem().string() + "-truth.json");
    f.scene = o.scene;
    if (!o.scene.empty() && o.scene.extension() != ".json")
        throw inputError("scene file " + o.scene.string(), "a scene file must end in .json",
                         "name it e.g. part.json");
    const std::vector<std::pair<std::string, std::filesystem::path>> files = {
        {"height map", f.heightmap},
        {"truth mask", f.truth},
        {"truth legend", f.legend},
        {"scene file", f.scene}};
    for (size_t i = 0; i < files.size(); ++i) {
        if (files[i].second.empty()) continue;
        std::error_code ec;
        if (std::filesystem::is_directory(files[i].second, ec))
            throw inputError(files[i].first + " " + files[i].second.string(), "is a directory",
                             "give a file name");
        for (size_t k = 0; k < i; ++k)
            if (sameFile(files[i].second, files[k].second))
                throw inputError(files[i].first + " " + files[i].second.string(),
                                 "is also the " + files[k].first + " of this run",
                                 "give the " + files[i].first + " another name");
    }
    return f;
}

PartFiles writePartFiles(const GeneratedSurface& g, const std::filesystem::path& out,
                         const PartFileOptions& o) {
    PartFiles f = checkPartFiles(out, o);
    const std::string ext = out.extension().string();
    // Staged: every file under a temporary name first, renamed into place together.
    AtomicOutput hmOut(f.heightmap), truthOut(f.truth), legendOut(f.legend);
    std::optional<AtomicOutput> sceneOut;
    if (!f.scene.empty()) sceneOut.emplace(f.scene);
    Image hm(g.width, g.height, 1);
    auto [mn, mx] = std::minmax_element(g.heights.begin(), g.heights.end());
    f.lo = *mn;
    f.hi = *mx > *mn ? *mx : *mn + 1e-6;
    if (ext == ".exr") {
        hm.data = g.heights;
        writeExr(hmOut.tempPath(), hm);
    } else if (ext == ".x3p") {
        writeX3p(hmOut.tempPath(), g.width, g.height, g.heights, g.pitch);
    } else {
        for (size_t i = 0; i < g.heights.size(); ++i)
            hm.data[i] = static_cast<float>((g.heights[i] - f.lo) / (f.hi - f.lo));
        writePng16(hmOut.tempPath(), hm);
    }
    throwIfInterrupted();  // between the files: a big map's encoding takes seconds
    // The legend of the truth labels (judge --truth reads it to name the regions): every label
    // present (synth/SurfaceGenerator.h truthLegend).
    nlohmann::ordered_json legend;
    legend["labels"] = nlohmann::ordered_json::array();
    for (const RegionLabel& l : truthLegend(g.truth))
        legend["labels"].push_back({{"value", l.value}, {"name", l.name}});
    for (const auto& [key, value] : o.legendExtra.items()) legend[key] = value;
    writeMaskPng(truthOut.tempPath(), g.truth, g.width, g.height);
    writeTextAtomically(legendOut.tempPath(), legend.dump(2) + "\n");

    if (!o.scene.empty()) {
        nlohmann::ordered_json hmj;
        hmj["path"] = std::filesystem::relative(std::filesystem::absolute(out),
                                                std::filesystem::absolute(o.scene).parent_path())
                          .generic_string();
        if (ext != ".x3p") hmj["pixel_pitch"] = g.pitch;  // an X3P file carries its pitch
        if (ext == ".png") hmj["height_range"] = {f.lo, f.hi};
        // an X3P file reads as a measurement, the other formats as a simulator's: say so only
        // where the part is the other (a generated part in X3P, defects in a measured texture)
        if (o.measured != (ext == ".x3p")) hmj["measured"] = o.measured;
        nlohmann::ordered_json j;
        j["description"] = g.description;
        j["heightmap"] = hmj;
        j["material"] = {{"type", "roughconductor"},
                         {"distribution", "ggx"},
                         {"alpha", 0.05},
                         {"material", "Al"}};
        if (o.imageSize > 0) j["camera"] = {{"width", o.imageSize}, {"height", o.imageSize}};
        const EnvMapDesc grid;  // the default env-map grid (scene/Scene.h)
        j["envmap"] = {{"width", grid.width}, {"height", grid.height}};
        j["render"] = {{"spp", o.spp}, {"max_depth", o.maxDepth}, {"seed", 0}};
        writeTextAtomically(sceneOut->tempPath(), j.dump(2) + "\n");
    }
    enterCommit();  // Ctrl-C before the files appear: none of them does; after: all of them
    hmOut.commit();
    truthOut.commit();
    legendOut.commit();
    if (sceneOut) sceneOut->commit();
    return f;
}

}  // namespace sl
