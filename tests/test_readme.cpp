// The README's "Scene file" table is the parser's own list of fields and defaults
// (io/SceneFile.h sceneFileFields()), and each default is defined once: the parser applies the
// defaults of the scene structs, and the renderer's options agree with the scene's render section;
// the Layout section names every folder; the optimizer table names every registered method;
// every `scratchlight COMMAND ... --flag` the README shows names a command and flags it has.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "io/SceneFile.h"
#include "optimize/Methods.h"
#include "render/PathTracer.h"
#include "scene/Scene.h"

using namespace sl;

namespace {

std::string readmeText() {
    std::ifstream in(SL_SOURCE_DIR "/README.md");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string readmeSection(const std::string& heading) {
    const std::string text = readmeText();
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

/// The README's command lines: its code spans (across line breaks, whitespace collapsed) and the
/// lines of its code blocks (fenced, or indented by 4 or more spaces) that start with
/// `scratchlight `.
std::vector<std::string> readmeCode(const std::string& text) {
    std::vector<std::string> code;
    std::string prose;  // the text outside fenced blocks, for the code spans
    std::istringstream in(text);
    bool fenced = false;
    for (std::string line; std::getline(in, line);) {
        const size_t first = line.find_first_not_of(' ');
        const std::string stripped = first == std::string::npos ? "" : line.substr(first);
        if (stripped.rfind("```", 0) == 0) {
            fenced = !fenced;
            continue;
        }
        if (fenced ||
            (first != std::string::npos && first >= 4 && stripped.find('`') == std::string::npos)) {
            if (stripped.rfind("scratchlight ", 0) == 0) code.push_back(stripped);
            if (fenced) continue;
        }
        prose += line + "\n";
    }
    static const std::regex span("`([^`]+)`");
    for (std::sregex_iterator it(prose.begin(), prose.end(), span), end; it != end; ++it)
        code.push_back(std::regex_replace((*it)[1].str(), std::regex(R"(\s+)"), " "));
    return code;
}

}  // namespace

TEST(Readme, EveryCommandLineNamesACommandAndItsFlags) {
    // `scratchlight WORD ...` (and `scratchlight bench WORD ...`): WORD must be a command whose
    // --help lists each --flag that follows it in the same code span or line.
    static const std::regex command(R"(scratchlight ([a-z][a-z-]*)((?: [a-z][a-z-]*)?))");
    static const std::regex flag(R"((^|[^\w-])(--[a-z][a-z0-9-]*))");
    std::map<std::string, test::RunResult> help;
    int checked = 0;
    for (const std::string& line : readmeCode(readmeText())) {
        std::smatch m;
        if (!std::regex_search(line, m, command)) continue;
        std::string name = m[1];
        const std::string next = m[2].str().empty() ? "" : m[2].str().substr(1);
        if (name == "bench" && !next.empty()) name += " " + next;
        if (!help.count(name)) help[name] = test::runCli(name + " --help");
        const test::RunResult& h = help[name];
        ASSERT_EQ(h.exitCode, 0) << "README: `" << line << "`: `scratchlight " << name
                                 << " --help` fails:\n"
                                 << h.output;
        const std::string rest = m.suffix();
        for (std::sregex_iterator it(rest.begin(), rest.end(), flag), end; it != end; ++it) {
            const std::string f = (*it)[2];
            const std::regex listed("(^|[^\\w-])" + f + "([^\\w-]|$)");
            EXPECT_TRUE(std::regex_search(h.output, listed))
                << "README: `" << line << "` gives `scratchlight " << name << "` " << f
                << ", which its --help does not list";
            ++checked;
        }
    }
    EXPECT_GT(checked, 50) << "the README's command lines were not found";
}

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

TEST(Readme, LayoutListsEveryWingOfApp) {
    const std::string layout = readmeSection("## Layout");
    ASSERT_FALSE(layout.empty()) << "README.md has no \"## Layout\" section";
    int wings = 0;
    for (const auto& e : std::filesystem::directory_iterator(SL_SOURCE_DIR "/src/app"))
        if (e.is_directory()) {
            ++wings;
            const std::string name = "src/app/" + e.path().filename().string() + "/";
            EXPECT_NE(layout.find(name), std::string::npos) << name << " is missing from Layout";
        }
    EXPECT_GE(wings, 1) << "src/app/ has no wings";
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
