// Shared helpers of the CLI commands (argument plumbing only; the work is in the library).
#pragma once

#include <CLI/CLI.hpp>
#include <atomic>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "app/host/ExternalRenderer.h"
#include "app/pipeline/Cache.h"
#include "app/pipeline/Truth.h"
#include "core/Communicator.h"
#include "core/Error.h"
#include "core/Registry.h"
#include "scene/EnvMap.h"

namespace sl {
struct Scene;
}

namespace sl::cli {

/// The command line as typed (main.cpp sets it; jobs record it in their summaries).
inline std::string& invokedCommandLine() {
    static std::string line;
    return line;
}

/// The MPI ranks this process runs with (main.cpp sets them, app/host/Mpi.h; null before): only
/// `optimize` runs over several, and only rank 0 prints results.
inline const Communicator*& worldRanks() {
    static const Communicator* ranks = nullptr;
    return ranks;
}

/// The size of the allocation that failed when std::bad_alloc was thrown by operator new
/// (0: unknown; Memory.cpp).
extern std::atomic<size_t> gFailedAllocationBytes;

/// Exit codes of every command.
enum Exit : int { kOk = 0, kRuntimeError = 1, kUsageError = 2 };

/// A usage error detected after parsing (bad combination of options): exit code 2.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// The library names its options as "option 'NAME'" (core/Error.h option()); the command line
/// shows each as its flag --NAME where some command of `app` has that flag.
std::string withFlags(const CLI::App& app, const std::string& message);

/// The env map for a scene: --envmap SPEC (io/EnvMapIO.h lightFromSpec), else the scene's envmap
/// section, else the "studio" preset.
EnvMap chooseEnvMap(const Scene& scene, const std::string& spec);

/// A command that reads a scene file takes scene overrides: -D key=value (repeatable, as
/// Mitsuba's; io/SceneFile.h) and, when it renders (`image`), --width/--height and --size N
/// (both) for the image, which are camera.width/height overrides.
void addSceneOverrides(CLI::App* c, std::vector<std::string>& overrides, bool image);

/// The input of a command that reads a height map (io/SceneFile.h loadHeightSource: info,
/// defectmap, insert-defects, scratchmap): the required positional `input`, a height map in any
/// format a reader reads or a scene file (JSON) whose height map it reads, and the scene
/// overrides a scene file takes (addSceneOverrides without the image's: these commands render
/// nothing). `help` says what the command reads of each.
void addHeightSourceInput(CLI::App* c, std::filesystem::path& input,
                          std::vector<std::string>& overrides, const std::string& help);

/// --defects and --reference of the defects objective (app/pipeline/Truth.h RegionSpec) for a
/// command that optimizes a light (optimize, lamps). Defined after addParsed below.
void addDefectRegionOptions(CLI::App* c, RegionSpec& defects, RegionSpec& reference);

/// --renderer, --renderer-cmd (implies --renderer command), --renderer-timeout.
void addRendererOptions(CLI::App* c, RendererKind& kind, ExternalRendererOptions& external);

/// --cache DIR and --no-cache of a command that keeps traced matrices (app/pipeline/Cache.h).
void addCacheOptions(CLI::App* c, CacheLocation& cache);

/// A finite number > 0 (positiveNumber) or >= 0 (nonNegativeNumber), refused as "--flag: must be
/// a finite number > 0, got X" (CLI11's PositiveNumber printed its bounds as 309-digit numbers).
CLI::Validator positiveNumber();
CLI::Validator nonNegativeNumber();

/// An integer (integerInRange) or a finite number (numberInRange) in [lo, hi], refused as
/// "--flag: must be an integer in 1..16384, got '0'" (CLI11's Range said "Value abc not in range
/// 1 to 16384" for a word and printed its float bounds as -90.000000). inRange picks by the
/// bounds' type, so `inRange(1, 8)` takes integers and `inRange(-90.0, 90.0)` numbers.
CLI::Validator integerInRange(long long lo, long long hi);
CLI::Validator numberInRange(double lo, double hi);
template <typename T>
CLI::Validator inRange(T lo, T hi) {
    if constexpr (std::is_integral_v<T>)
        return integerInRange(lo, hi);
    else
        return numberInRange(lo, hi);
}

/// A size in bytes with an optional unit (b, kb = 1000 b, kib = 1024 b, mb, mib, gb, gib, tb,
/// tib; any case), e.g. 500MB or 8GB; CLI::ValidationError naming `flag` otherwise.
uintmax_t parseByteSize(const std::string& text, const std::string& flag);

/// A list of numbers "A,B,C" (a flag may also be given again): every entry a finite number,
/// none empty ("1,,3" is refused). CLI::ValidationError naming `flag` otherwise (a usage error:
/// it is thrown while the command line is parsed).
std::vector<double> parseNumberList(const std::vector<std::string>& texts, const std::string& flag);

/// Checks an output path ends in `ext` (usage error otherwise) and returns the sibling with
/// extension `siblingExt` (e.g. the PNG preview next to an EXR).
std::filesystem::path siblingPath(const std::filesystem::path& out, const std::string& ext,
                                  const std::string& siblingExt);

/// The one check of an OUTDIR that a run replaces as a whole (optimize, judge, lamps -o;
/// io/StagedDirectory.h checks the folder itself): it must not be, or hold, what the run reads:
/// `input` (a scene .json, a .tm or .shards), the files a scene names (its height map, ...) and
/// `others` (truth masks, region files, lights; names of no file, such as presets, are
/// skipped). Throws InputError naming the directory and the input (io/InputFile.h
/// refuseOutputOverInput).
void refuseOutputDirOverInputs(const std::filesystem::path& outDir,
                               const std::filesystem::path& input,
                               const std::vector<std::string>& sceneOverrides,
                               std::vector<std::filesystem::path> others);

/// Runs the plotting script `script` (a name under scripts/, found beside the executable, or a
/// path) with python3 and `args` when `run`; otherwise prints the command that would. Prints
/// "no plot: ..." when the script or python3 is missing; a failing script is a runtime error.
int runPlot(const std::string& script, const std::vector<std::string>& args, bool run);

/// An option whose values are the names of a registry's rows (core/Registry.h): `--help` lists
/// every row with its help text, a name outside the table is a usage error listing them, and
/// the value is parsed into the row's enum (into `target`, plain or std::optional) once, here.
template <class Row, class Target>
CLI::Option* addChoice(CLI::App* c, const std::string& flag, Target& target,
                       std::span<const Row> table, std::string description) {
    std::vector<std::string> names;
    for (const Row& r : table) {
        names.emplace_back(r.name);
        description += std::string("\n    ") + r.name + ": " + r.help;
    }
    return c
        ->add_option_function<std::string>(
            flag,
            [&target, table](const std::string& v) { target = findRegistryRow(table, v)->value; },
            description)
        ->check(CLI::IsMember(names));
}

/// An option parsed once by the library's parser `parse(text, where)` (where = the flag); its
/// InputError leaves parsing and exits 1 with the message, as every input error (main.cpp).
template <class Target, class Parse>
CLI::Option* addParsed(CLI::App* c, const std::string& flag, Target& target, Parse parse,
                       const std::string& description) {
    return c->add_option_function<std::string>(
        flag, [&target, parse, flag](const std::string& v) { target = parse(v, flag); },
        description);
}

/// "A:B" as two numbers of type T (int: std::stoi, double: std::stod), each taking its whole
/// side of the colon; nullopt when the text is not that. The caller names the flag in its error.
template <class T>
std::optional<std::pair<T, T>> parseColonPair(const std::string& text) {
    const size_t colon = text.find(':');
    if (colon == std::string::npos) return std::nullopt;
    auto number = [](const std::string& s) -> std::optional<T> {
        try {
            size_t used = 0;
            T v;
            if constexpr (std::is_same_v<T, int>)
                v = std::stoi(s, &used);
            else
                v = std::stod(s, &used);
            if (used != s.size()) return std::nullopt;
            return v;
        } catch (const std::logic_error&) {
            return std::nullopt;
        }
    };
    const auto a = number(text.substr(0, colon)), b = number(text.substr(colon + 1));
    if (!a || !b) return std::nullopt;
    return std::pair<T, T>{*a, *b};
}

}  // namespace sl::cli
