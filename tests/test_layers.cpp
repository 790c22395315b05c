// The house rules that are facts about the source tree (docs/DESIGN.md "Layers"):
//   - a folder of src/ includes only the folders its row of the layers table lists;
//   - files are opened only in io/ and app/ (the CLI and the lower layers call them);
//   - no command-line flag ("--name") is spelled outside src/cli.
// The table is read from docs/DESIGN.md, so the page and the code cannot drift apart.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>

namespace {

namespace fs = std::filesystem;

std::string readFile(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

/// DESIGN.md's layers table: folder → the folders it may include (itself always).
std::map<std::string, std::set<std::string>> layerTable() {
    std::map<std::string, std::set<std::string>> t;
    std::istringstream in(readFile(SL_SOURCE_DIR "/docs/DESIGN.md"));
    const std::regex row(R"(^\| `src/([a-z]+)/` \|.*\| ([^|]*) \|\s*$)");
    std::vector<std::string> order;
    for (std::string line; std::getline(in, line);) {
        std::smatch m;
        if (!std::regex_match(line, m, row)) continue;
        const std::string folder = m[1], includes = m[2];
        std::set<std::string> allowed{folder};
        if (includes.find("everything") != std::string::npos) {
            allowed.insert(order.begin(), order.end());
        } else {
            const std::regex word("[a-z]+");
            for (std::sregex_iterator w(includes.begin(), includes.end(), word), e; w != e; ++w)
                if (w->str() != "nothing" && w->str() != "of" && w->str() != "ours")
                    allowed.insert(w->str());
        }
        order.push_back(folder);
        t[folder] = allowed;
    }
    return t;
}

struct Source {
    std::string folder, name, text;
};

std::vector<Source> sources() {
    std::vector<Source> out;
    for (const auto& e : fs::recursive_directory_iterator(SL_SOURCE_DIR "/src")) {
        const auto ext = e.path().extension();
        if (ext != ".h" && ext != ".cpp") continue;
        // The folder is the first one under src/ (app/'s wings are checked as app).
        const fs::path rel = fs::relative(e.path(), SL_SOURCE_DIR "/src");
        out.push_back({rel.begin()->string(), rel.generic_string(), readFile(e.path())});
    }
    return out;
}

/// The text without comments and without the contents of string literals.
std::string code(const std::string& text) {
    static const std::regex comment(R"(//[^\n]*)");
    return std::regex_replace(text, comment, "");
}

}  // namespace

TEST(Layers, EveryFolderIsInTheTableAndIncludesOnlyTheLayersItLists) {
    const auto table = layerTable();
    ASSERT_GE(table.size(), 10u) << "docs/DESIGN.md's layers table was not found";
    const std::regex include(R"re(#include "([a-z]+)/)re");
    for (const Source& s : sources()) {
        ASSERT_TRUE(table.count(s.folder)) << "src/" << s.folder << "/ is not in DESIGN.md";
        const auto& allowed = table.at(s.folder);
        for (std::sregex_iterator m(s.text.begin(), s.text.end(), include), e; m != e; ++m)
            EXPECT_TRUE(allowed.count((*m)[1].str()))
                << s.name << " includes " << (*m)[1] << "/, which its layer may not";
    }
}

TEST(Layers, OnlyIoAndAppOpenFiles) {
    const std::regex opens(
        R"(std::[io]?fstream|std::fopen|\bfopen\(|ImageInput::open|ImageOutput::create)");
    for (const Source& s : sources()) {
        if (s.folder == "io" || s.folder == "app") continue;
        EXPECT_FALSE(std::regex_search(code(s.text), opens)) << s.name << " opens a file";
    }
}

TEST(Layers, OnlyTheCommandLineSpellsFlags) {
    const std::regex literal(R"re("([^"\\\n]|\\.)*")re"), flag(R"((^|[^-\w])--[a-z])");
    for (const Source& s : sources()) {
        if (s.folder == "cli") continue;
        const std::string c = code(s.text);
        for (std::sregex_iterator m(c.begin(), c.end(), literal), e; m != e; ++m)
            EXPECT_FALSE(std::regex_search(m->str(), flag))
                << s.name << " spells a command-line flag in " << m->str()
                << "; name the option with option(\"name\")";
    }
}
