// One grammar for every command (the command line's contract): walks `--help-all` for the
// commands and each command's --help for its flags, and checks one name per concept (-o for
// every output, --width/--height/--size and --spp/--seed/--max-depth on every command that
// renders, -D on every command that reads a scene, no retired synonyms); then that -D,
// --size and --envmap SPEC do what they say, from any directory; and that every `bench X` is
// listed where the benchmarks are listed (README, DESIGN).
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "TestUtil.h"
#include "io/ImageIO.h"

using namespace sl;
using test::runCli;

namespace {

/// The names listed under "Subcommands:" in a help text.
std::vector<std::string> subcommandsIn(const std::string& help) {
    std::vector<std::string> names;
    std::istringstream in(help);
    bool inside = false;
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("Subcommands:", 0) == 0) {
            inside = true;
            continue;
        }
        if (!inside) continue;
        static const std::regex row(R"(^  ([a-z][a-z0-9-]*)\s)");
        std::smatch m;
        if (std::regex_search(line, m, row))
            names.push_back(m[1]);
        else if (!line.empty() && line[0] != ' ')
            inside = false;
    }
    return names;
}

struct Grammar {
    std::set<std::string> flags, positionals;
};

/// A command's flags (every -x and --name of its option rows) and positional names.
Grammar grammarOf(const std::string& help) {
    Grammar g;
    std::istringstream in(help);
    std::string section;
    for (std::string line; std::getline(in, line);) {
        if (!line.empty() && line[0] != ' ') {
            section = line;
            continue;
        }
        if (section.rfind("Options:", 0) == 0 && line.rfind("  -", 0) == 0) {
            const std::string head = line.substr(2, line.find(' ', 2) - 2);  // "-o,--output"
            static const std::regex flag(R"(-{1,2}[A-Za-z][A-Za-z0-9-]*)");
            for (std::sregex_iterator it(head.begin(), head.end(), flag), end; it != end; ++it)
                g.flags.insert(it->str());
        } else if (section.rfind("Positionals:", 0) == 0 && line.rfind("  ", 0) == 0 &&
                   line.size() > 2 && line[2] != ' ') {
            g.positionals.insert(line.substr(2, line.find(' ', 2) - 2));
        }
    }
    return g;
}

/// Whether `s` is well-formed UTF-8 (lead bytes, continuation bytes, no truncation).
bool validUtf8(const std::string& s) {
    for (size_t i = 0; i < s.size();) {
        const auto b = static_cast<unsigned char>(s[i]);
        const size_t n = b < 0x80           ? 1
                         : (b >> 5) == 0x6  ? 2
                         : (b >> 4) == 0xE  ? 3
                         : (b >> 3) == 0x1E ? 4
                                            : 0;
        if (n == 0 || i + n > s.size()) return false;
        for (size_t k = 1; k < n; ++k)
            if ((static_cast<unsigned char>(s[i + k]) >> 6) != 0x2) return false;
        i += n;
    }
    return true;
}

}  // namespace

TEST(CliGrammar, EveryCommandFollowsOneGrammar) {
    const auto all = runCli("--help-all");
    ASSERT_EQ(all.exitCode, 0) << all.output;
    // Every command --help-all shows, with the nested ones (bench ..., cache clear).
    std::vector<std::string> commands;
    for (const std::string& c : subcommandsIn(runCli("--help").output)) {
        EXPECT_NE(all.output.find("\n" + c + "\n"), std::string::npos) << c << " not in --help-all";
        const auto help = runCli(c + " --help");
        const auto nested = subcommandsIn(help.output);
        if (nested.empty() || c == "cache") commands.push_back(c);
        for (const std::string& n : nested) commands.push_back(c + " " + n);
    }
    ASSERT_GE(commands.size(), 20u);

    // Retired names: one name per concept.
    const std::map<std::string, std::string> retired = {{"--out", "-o,--output"},
                                                        {"--csv", "-o,--output"},
                                                        {"--json", "-o,--output"},
                                                        {"--resolution", "--size"},
                                                        {"--h", "--fd-step"},
                                                        {"--fd-h", "--fd-step"},
                                                        {"--fd-steps", "--fd-step"},
                                                        {"--constant", "--envmap const:V"},
                                                        {"--image-mask", "--image-output"},
                                                        {"--image-out", "--image-output"},
                                                        {"--judge-spp", "--heldout-spp"}};
    // gen-surface keeps --image-size: the image size it writes into the scene file, beside its
    // --width/--height of the height map it makes (it renders nothing).
    // Commands that write no file.
    const std::set<std::string> noOutput = {"cache", "cache clear"};
    // Commands that render: the image and sampling overrides.
    const std::set<std::string> rendering = {"render", "precompute", "optimize",
                                             "judge",  "gradcheck",  "bench gradients"};
    // Benchmarks that render at a size of their own (and sweep or fix the sampling).
    const std::set<std::string> benchSized = {"bench render", "bench transport", "bench noise"};
    const std::set<std::string> readsScene = {
        "render",          "precompute",  "optimize",       "judge",          "gradcheck",
        "export-mitsuba",  "scratchmap",  "defectmap",      "insert-defects", "bench render",
        "bench transport", "bench noise", "bench gradients"};
    for (const std::string& c : commands) {
        SCOPED_TRACE(c);
        const auto help = runCli(c + " --help");
        ASSERT_EQ(help.exitCode, 0) << help.output;
        EXPECT_TRUE(validUtf8(help.output)) << "a default printed as a raw byte?\n" << help.output;
        const Grammar g = grammarOf(help.output);
        for (const auto& [name, use] : retired) {
            EXPECT_EQ(g.flags.count(name), 0u) << name << " is spelled " << use << " elsewhere";
        }
        for (const char* p : {"output", "out", "outdir"}) {
            EXPECT_EQ(g.positionals.count(p), 0u) << "an output is -o, not the positional " << p;
        }
        if (!noOutput.count(c)) {
            EXPECT_TRUE(g.flags.count("-o") && g.flags.count("--output")) << help.output;
        }
        if (rendering.count(c)) {
            for (const char* f : {"--width", "--height", "--size", "--spp", "--max-depth"}) {
                EXPECT_TRUE(g.flags.count(f)) << f << "\n" << help.output;
            }
        }
        if (rendering.count(c) && c.rfind("bench", 0) != 0) {
            EXPECT_TRUE(g.flags.count("--seed")) << help.output;
        }
        if (benchSized.count(c)) {
            EXPECT_TRUE(g.flags.count("--size")) << help.output;
        }
        if (readsScene.count(c)) {
            EXPECT_TRUE(g.flags.count("-D")) << help.output;
        }
    }
}

// Every `bench X` is listed where the benchmarks are listed: the README's command table (its
// `scratchlight bench (...)` row) and DESIGN's "Tests and benchmarks" (`scratchlight bench ...`).
TEST(CliGrammar, EveryBenchIsListedInTheReadmeAndDesign) {
    const auto bench = runCli("bench --help");
    ASSERT_EQ(bench.exitCode, 0) << bench.output;
    const std::vector<std::string> benches = subcommandsIn(bench.output);
    ASSERT_GE(benches.size(), 16u) << bench.output;
    // The names of a `bench A | B | ...` list: the words between the bars, from `bench` to the
    // first character that is neither a name, a space nor a bar.
    auto listAfter = [](const std::string& text, const std::string& start, size_t from = 0) {
        std::set<std::string> names;
        const size_t at = from == std::string::npos ? from : text.find(start, from);
        if (at == std::string::npos) return names;
        static const std::regex item(R"(^\s*(?:\\)?\|?\s*([a-z][a-z0-9-]*))");
        std::string rest = text.substr(at + start.size());
        for (std::smatch m; std::regex_search(rest, m, item); rest = m.suffix()) names.insert(m[1]);
        return names;
    };
    const std::string readme = test::readFile(SL_SOURCE_DIR "/README.md");
    const std::string design = test::readFile(SL_SOURCE_DIR "/docs/DESIGN.md");
    const std::set<std::string> inReadme = listAfter(readme, "| `scratchlight bench (");
    const std::set<std::string> inDesign =
        listAfter(design, "`scratchlight bench ", design.find("\n## Tests and benchmarks\n"));
    for (const std::string& b : benches) {
        EXPECT_TRUE(inReadme.count(b)) << "README's bench row does not list " << b;
        EXPECT_TRUE(inDesign.count(b)) << "DESIGN's \"Tests and benchmarks\" does not list " << b;
    }
}

// The small things: a mistyped flag gets the nearest one; a light that is neither a file nor a
// name gets the names, const:V and where a relative path was looked for; -q keeps only results,
// warnings and errors; export-mitsuba says what it wrote.
TEST(CliGrammar, MistakesGetSuggestionsAndQuietIsQuiet) {
    test::TempDir dir("grammar");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    auto r = runCli("render " + scene + " --sizee 256 -o " + (dir / "a.exr").string());
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("--sizee: did you mean --size?"), std::string::npos) << r.output;
    r = runCli("optimize " + scene + " --iteratoins=5 -o " + (dir / "o").string());
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find("--iteratoins: did you mean --iterations?"), std::string::npos)
        << r.output;

    r = runCli("render " + scene + " --size 8 --spp 1 --envmap studioo -o " +
               (dir / "b.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    for (const char* part :
         {"--envmap 'studioo'", "neither a light name nor a file",
          "resolved against the working directory", "Did you mean 'studio'", "const:V", "studio"})
        EXPECT_NE(r.output.find(part), std::string::npos) << part << " not in: " << r.output;

    r = runCli("render -q " + scene + " --size 8 --spp 1 --envmap const:0.5 -o " +
               (dir / "c.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output, "") << "render -q printed";
    r = runCli("render " + scene + " --size 8 --spp 1 --envmap const:0.5 -o " +
               (dir / "c.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("part part.exr (exr float32): 1024 x 1024 samples, pitch 0.01 mm, "
                            "10.23 x 10.23 mm"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("wrote " + (dir / "c.exr").string()), std::string::npos) << r.output;

    r = runCli("export-mitsuba " + scene + " --size 8 -o " + (dir / "m").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("wrote " + (dir / "m").string()), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("mitsuba -m scalar_rgb"), std::string::npos) << r.output;
}

TEST(CliGrammar, SceneOverridesReachTheRenderAndNameTheirMistakes) {
    test::TempDir dir("grammar");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    // --size and -D camera.* give the image its size; -D render.spp is the sampling.
    auto r = runCli("render " + scene + " --size 24 -D render.spp=2 --envmap const:0.5 -o " +
                    (dir / "a.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("rendered 24x24 at 2 spp"), std::string::npos) << r.output;
    r = runCli("render " + scene + " -D camera.width=20 -D camera.height=12 --spp 1 -o " +
               (dir / "b.exr").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const Image b = readImage(dir / "b.exr");
    EXPECT_EQ(b.width, 20);
    EXPECT_EQ(b.height, 12);
    // A field the scene does not have is named, with the override that brought it.
    r = runCli("render " + scene + " -D material.alhpa=0.1 --size 8 --spp 1 -o " +
               (dir / "c.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("alhpa"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("-D material.alhpa=0.1"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir / "c.exr"));
    // Not key=value.
    r = runCli("render " + scene + " -D material.alpha --size 8 --spp 1 -o " +
               (dir / "d.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("key=value"), std::string::npos) << r.output;
    // A bad light spec is a usage error naming the form.
    r = runCli("render " + scene + " --envmap const:bright --size 8 --spp 1 -o " +
               (dir / "e.exr").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--envmap const:bright"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("const:V"), std::string::npos) << r.output;
}

TEST(CliGrammar, OverridesOfATracedMatrixAreRefusedAndRecordedInIts) {
    test::TempDir dir("grammar-tm");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string tm = (dir / "p.tm").string();
    auto r = runCli("precompute " + scene +
                    " --size 16 --spp 2 --halves -D material.alpha=0.2 -o " + tm);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("16x16 px"), std::string::npos) << r.output;
    // optimize from the .tm re-reads the scene with the same overrides (the held-out estimate
    // must match T's camera and material).
    r = runCli("optimize " + tm + " --iterations 3 --heldout-spp 4 -o " + (dir / "o").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    r = runCli("optimize " + tm + " --size 32 -o " + (dir / "p").string());
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("--size"), std::string::npos) << r.output;
}

TEST(CliGrammar, DefaultsWorkFromAnyDirectory) {
    test::TempDir dir("grammar-cwd");
    // bench transport's default scene is the bundled one, found beside the executable.
    const std::string cmd = "cd " + dir.path().string() + " && " + std::string(SL_CLI_PATH) +
                            " bench transport --size 16 --spp 1 --iterations 2 --repeats 1 2>&1";
    FILE* f = popen(cmd.c_str(), "r");
    ASSERT_NE(f, nullptr);
    std::string out;
    char buf[4096];
    for (size_t n; (n = fread(buf, 1, sizeof buf, f)) > 0;) out.append(buf, n);
    EXPECT_EQ(pclose(f), 0) << out;
    EXPECT_NE(out.find("scenes/default (bundled)"), std::string::npos) << out;
    EXPECT_TRUE(std::filesystem::exists(dir / "bench-transport.csv"));
}
