// The house rules that are facts about the source tree (docs/DESIGN.md "Layers"):
//   - a folder of src/ includes only the folders its row of the layers table lists;
//   - files are opened only in io/ and app/ (the CLI and the lower layers call them);
//   - no command-line flag ("--name") is spelled outside src/cli;
//   - app/ holds only its wings, each including only the wings its row of the wings table lists;
//   - no two modules (a header with its source file) include each other, directly or not;
//   - each command is registered in the CLI file named after it, and every `bench X` from the one
//     table (cli/BenchCmd.cpp benchCommands()).
// The table is read from docs/DESIGN.md, so the page and the code cannot drift apart.
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <functional>
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

/// DESIGN.md's wings table (app/'s wings): wing → the wings it may include (itself always).
std::map<std::string, std::set<std::string>> wingTable() {
    std::map<std::string, std::set<std::string>> t;
    std::istringstream in(readFile(SL_SOURCE_DIR "/docs/DESIGN.md"));
    const std::regex row(R"(^\| `src/app/([a-z]+)/` \|.*\| ([^|]*) \|\s*$)");
    for (std::string line; std::getline(in, line);) {
        std::smatch m;
        if (!std::regex_match(line, m, row)) continue;
        const std::string wing = m[1], includes = m[2];
        std::set<std::string> allowed{wing};
        const std::regex word("[a-z]+");
        for (std::sregex_iterator w(includes.begin(), includes.end(), word), e; w != e; ++w)
            if (w->str() != "nothing" && w->str() != "of" && w->str() != "app")
                allowed.insert(w->str());
        t[wing] = allowed;
    }
    return t;
}

/// The module a source belongs to: its path without the extension, a private header
/// (`X_impl.h`, `XDetail.h`) counted with X.
std::string moduleOf(std::string path) {
    path = path.substr(0, path.rfind('.'));
    for (const std::string suffix : {"_impl", "Detail"})
        if (path.size() > suffix.size() &&
            path.compare(path.size() - suffix.size(), suffix.size(), suffix) == 0)
            return path.substr(0, path.size() - suffix.size());
    return path;
}

using Graph = std::map<std::string, std::set<std::string>>;

/// The cycles of a directed graph: each strongly connected component of more than one node
/// (Tarjan's algorithm), its nodes sorted and joined by " <-> ".
std::set<std::string> cycles(Graph edges) {
    std::map<std::string, int> index, low;
    std::vector<std::string> stack;
    std::set<std::string> onStack, found;
    int next = 0;
    std::function<void(const std::string&)> visit = [&](const std::string& v) {
        index[v] = low[v] = next++;
        stack.push_back(v);
        onStack.insert(v);
        for (const std::string& w : edges[v]) {
            if (!index.count(w)) {
                visit(w);
                low[v] = std::min(low[v], low[w]);
            } else if (onStack.count(w)) {
                low[v] = std::min(low[v], index[w]);
            }
        }
        if (low[v] != index[v]) return;
        std::set<std::string> component;
        for (std::string w = ""; w != v;) {
            w = stack.back();
            stack.pop_back();
            onStack.erase(w);
            component.insert(w);
        }
        if (component.size() < 2) return;
        std::string joined;
        for (const std::string& m : component) joined += (joined.empty() ? "" : " <-> ") + m;
        found.insert(joined);
    };
    std::vector<std::string> modules;
    for (const auto& [m, _] : edges) modules.push_back(m);
    for (const std::string& m : modules)
        if (!index.count(m)) visit(m);
    return found;
}

/// The module graph of src/ (a module is a header with its source file): an edge from each
/// module to every module of ours it includes.
Graph includeGraph() {
    Graph edges;
    const std::regex include(R"re(#include "([^"]+\.h)")re");
    for (const Source& s : sources()) {
        const std::string from = moduleOf(s.name);
        edges[from];
        for (std::sregex_iterator m(s.text.begin(), s.text.end(), include), e; m != e; ++m) {
            const std::string to = moduleOf((*m)[1].str());
            if (to != from && fs::exists(SL_SOURCE_DIR "/src/" + (*m)[1].str()))
                edges[from].insert(to);
        }
    }
    return edges;
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

TEST(Layers, AppHasNoLooseFilesAndEachWingIncludesOnlyTheWingsItLists) {
    const auto wings = wingTable();
    ASSERT_GE(wings.size(), 6u) << "docs/DESIGN.md's wings table was not found";
    const std::regex include(R"re(#include "app/([a-z]+)/)re");
    for (const auto& e : fs::directory_iterator(SL_SOURCE_DIR "/src/app"))
        EXPECT_TRUE(e.is_directory() && wings.count(e.path().filename().string()))
            << e.path() << ": app/ holds only the wings DESIGN.md lists";
    for (const Source& s : sources()) {
        if (s.folder != "app") continue;
        const std::string wing = fs::path(s.name).begin()->string() == "app"
                                     ? std::next(fs::path(s.name).begin())->string()
                                     : "";
        ASSERT_TRUE(wings.count(wing)) << s.name << " is in no wing DESIGN.md lists";
        const auto& allowed = wings.at(wing);
        for (std::sregex_iterator m(s.text.begin(), s.text.end(), include), e; m != e; ++m)
            EXPECT_TRUE(allowed.count((*m)[1].str()))
                << s.name << " includes app/" << (*m)[1] << "/, which its wing may not";
    }
}

TEST(Layers, EachCommandIsInTheFileNamedAfterItAndEveryBenchInOneTable) {
    // A command `gen-surface` is added in cli/GenSurfaceCmd.cpp (case and dashes aside).
    const std::regex command(R"re(\bapp\.add_subcommand\(\s*"([a-z-]+)")re");
    const std::regex benchChild(R"(\bbench->add_subcommand\()"), findBench(R"re("bench"\))re");
    int commands = 0, benchAdds = 0;
    for (const Source& s : sources()) {
        if (s.folder != "cli") continue;
        const std::string c = code(s.text);
        for (std::sregex_iterator m(c.begin(), c.end(), command), e; m != e; ++m, ++commands) {
            std::string want;
            for (const char ch : (*m)[1].str())
                if (ch != '-') want += ch;
            std::string file = fs::path(s.name).filename().string();
            for (char& ch : file)
                ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
            EXPECT_EQ(file, want + "cmd.cpp") << "`" << (*m)[1] << "` is registered in " << s.name;
        }
        for (std::sregex_iterator m(c.begin(), c.end(), benchChild), e; m != e; ++m) {
            ++benchAdds;
            EXPECT_EQ(s.name, "cli/BenchCmd.cpp")
                << s.name << " adds a bench subcommand: add a row to benchCommands() instead";
        }
        EXPECT_FALSE(std::regex_search(c, findBench))
            << s.name << " looks the bench command up: its rows are in benchCommands()";
    }
    EXPECT_GE(commands, 15);
    EXPECT_EQ(benchAdds, 1) << "registerBench adds every row of benchCommands() in one loop";
}

TEST(Layers, ModulesIncludeEachOtherInNoCycle) {
    EXPECT_EQ(cycles(includeGraph()), std::set<std::string>{});
}

TEST(Layers, TheCycleFinderFindsEachCycleOnceAndNothingElse) {
    // a → b → c → a is one cycle; d → e → d another; c → d joins them one way only, and f → f
    // (a module including itself) and the chain g → h are none.
    const Graph g = {{"a", {"b"}}, {"b", {"c"}}, {"c", {"a", "d"}}, {"d", {"e"}},
                     {"e", {"d"}}, {"f", {"f"}}, {"g", {"h"}}};
    EXPECT_EQ(cycles(g), (std::set<std::string>{"a <-> b <-> c", "d <-> e"}));
    EXPECT_TRUE(cycles({{"g", {"h"}}, {"h", {}}}).empty());
    // A private header is counted with its module.
    EXPECT_EQ(moduleOf("optimize/OptimizerDetail.h"), "optimize/Optimizer");
    EXPECT_EQ(moduleOf("objective/Objective_impl.h"), "objective/Objective");
    EXPECT_EQ(moduleOf("app/pipeline/Judge.cpp"), "app/pipeline/Judge");
}
