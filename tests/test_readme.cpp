// The README's "Scene file" table is the parser's own list of fields and defaults
// (io/SceneFile.h sceneFileFields()), and each default is defined once: the parser applies the
// defaults of the scene structs, and the renderer's options agree with the scene's render section;
// the Layout section names every folder; the optimizer table names every registered method.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include "io/SceneFile.h"
#include "optimize/Methods.h"
#include "render/PathTracer.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

std::string readmeSection(const std::string& heading) {
    std::ifstream in(SL_SOURCE_DIR "/README.md");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = ss.str();
    const size_t start = text.find("\n" + heading + "\n");
    if (start == std::string::npos) return {};
    const size_t end = text.find("\n## ", start + 1);
    return text.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

/// The lines of the first Markdown table in `text`.
std::string firstTable(const std::string& text) {
    std::istringstream in(text);
    std::string table;
    bool inTable = false;
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("|", 0) == 0) {
            table += line + "\n";
            inTable = true;
        } else if (inTable) {
            break;
        }
    }
    return table;
}

}  // namespace

TEST(Readme, SceneFileTableIsTheParsersListOfFieldsAndDefaults) {
    const std::string section = readmeSection("## Scene file");
    ASSERT_FALSE(section.empty()) << "README.md has no \"## Scene file\" section";
    EXPECT_EQ(firstTable(section), sceneFileTable())
        << "README.md's scene-file table differs from io/SceneFile.cpp sceneFileFields(); the "
           "table to paste:\n"
        << sceneFileTable();
}

TEST(Readme, ParserAppliesTheDefaultsOfTheSceneStructs) {
    const SceneDesc d = parseScene(R"({"heightmap": {"path": "h.exr"}})", "/tmp", "test");
    const SceneDesc def;
    EXPECT_EQ(d.heightmap.pitch, def.heightmap.pitch);
    EXPECT_EQ(d.heightmap.heightScale, def.heightmap.heightScale);
    EXPECT_FALSE(d.heightmap.heightRange.has_value());
    EXPECT_EQ(d.material.type, def.material.type);
    EXPECT_EQ(d.material.name, def.material.name);
    EXPECT_EQ(d.material.params.smooth, def.material.params.smooth);
    EXPECT_EQ(d.material.params.distribution, def.material.params.distribution);
    EXPECT_EQ(d.material.params.alphaU, def.material.params.alphaU);
    EXPECT_EQ(d.material.params.alphaV, def.material.params.alphaV);
    EXPECT_EQ(d.material.params.alphaU, kDefaultAlpha);
    EXPECT_EQ(d.camera.type, def.camera.type);
    EXPECT_EQ(d.camera.fovDeg, def.camera.fovDeg);
    EXPECT_EQ(d.camera.width, def.camera.width);
    EXPECT_EQ(d.camera.height, def.camera.height);
    EXPECT_FALSE(d.camera.origin || d.camera.target || d.camera.up || d.camera.widthMm);
    EXPECT_EQ(d.envmap.width, def.envmap.width);
    EXPECT_EQ(d.envmap.height, def.envmap.height);
    EXPECT_TRUE(d.envmap.path.empty() && !d.envmap.constant && d.envmap.preset.empty());
    EXPECT_EQ(d.render.spp, def.render.spp);
    EXPECT_EQ(d.render.maxDepth, def.render.maxDepth);
    EXPECT_EQ(d.render.seed, def.render.seed);
    // The camera's own defaults are the scene's.
    EXPECT_EQ(def.camera.fovDeg, CameraDesc{}.fovDeg);
    EXPECT_EQ(def.camera.width, CameraDesc{}.width);
}

TEST(Readme, RendererDefaultsAreTheSceneFilesRenderSection) {
    const RenderOptions o;
    const RenderDesc r;
    EXPECT_EQ(o.spp, r.spp);
    EXPECT_EQ(o.maxDepth, r.maxDepth);
    EXPECT_EQ(o.seed, r.seed);
}

TEST(Readme, LayoutListsEveryFolder) {
    const std::string layout = readmeSection("## Layout");
    ASSERT_FALSE(layout.empty()) << "README.md has no \"## Layout\" section";
    for (const auto& e : std::filesystem::directory_iterator(SL_SOURCE_DIR "/src"))
        if (e.is_directory()) {
            const std::string name = "src/" + e.path().filename().string() + "/";
            EXPECT_NE(layout.find(name), std::string::npos) << name << " is missing from Layout";
        }
    for (const char* top : {"tests/", "scripts/", "scenes/", "docs/"})
        EXPECT_NE(layout.find(top), std::string::npos) << top << " is missing from Layout";
}

TEST(Readme, OptimizerTableNamesEveryRegisteredMethod) {
    const std::string section = readmeSection("### Optimizers (`--optimizer`)");
    ASSERT_FALSE(section.empty()) << "README.md has no \"### Optimizers\" section";
    std::set<std::string> named;  // `name` in the table's first column
    std::istringstream in(firstTable(section));
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("| `", 0) != 0) continue;
        const std::string first = line.substr(0, line.find(" |", 2));
        for (size_t a = first.find('`'); a != std::string::npos; a = first.find('`', a + 1)) {
            const size_t b = first.find('`', a + 1);
            named.insert(first.substr(a + 1, b - a - 1));
            a = b;
        }
    }
    std::set<std::string> registered;
    for (const OptimizerMethodRow& r : optimizerMethodTable()) registered.insert(r.name);
    EXPECT_EQ(named, registered) << "README.md's optimizer table differs from optimize/Methods.cpp";
}
