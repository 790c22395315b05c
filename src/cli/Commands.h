// Each command registers its CLI11 subcommand and, when chosen, sets `run`; each is defined in
// the file named after it (cli/XCmd.cpp), and main.cpp calls them in `--help`'s order.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

namespace sl::cli {

void registerRender(CLI::App& app, std::function<int()>& run);
void registerGenSurface(CLI::App& app, std::function<int()>& run);
void registerInsertDefects(CLI::App& app, std::function<int()>& run);
void registerPrecompute(CLI::App& app, std::function<int()>& run);
void registerRelight(CLI::App& app, std::function<int()>& run);
void registerOptimize(CLI::App& app, std::function<int()>& run);
void registerJudge(CLI::App& app, std::function<int()>& run);
void registerBench(CLI::App& app, std::function<int()>& run);  // every row of benchCommands()
void registerGradCheck(CLI::App& app, std::function<int()>& run);
void registerExportMitsuba(CLI::App& app, std::function<int()>& run);
void registerScratchMap(CLI::App& app, std::function<int()>& run);
void registerReport(CLI::App& app, std::function<int()>& run);
void registerEnvMapPreset(CLI::App& app, std::function<int()>& run);
void registerDefectMap(CLI::App& app, std::function<int()>& run);
void registerCache(CLI::App& app, std::function<int()>& run);
void registerLamps(CLI::App& app, std::function<int()>& run);
void registerView(CLI::App& app, std::function<int()>& run);
void registerInfo(CLI::App& app, std::function<int()>& run);

/// One `bench X`: its name, its help line, and what adds its options to the subcommand and, when
/// chosen, sets `run`.
struct BenchCommand {
    const char* name;
    const char* help;
    void (*add)(CLI::App* c, std::function<int()>& run);
};

/// Every `bench X`, in `bench --help`'s order: the one table registerBench adds (cli/BenchCmd.cpp).
const std::vector<BenchCommand>& benchCommands();

// The rows defined beside the command whose options they share.
void addRaceBench(CLI::App* c, std::function<int()>& run);       // cli/RaceCmd.cpp
void addSettingsBench(CLI::App* c, std::function<int()>& run);   // cli/RaceCmd.cpp
void addGradientsBench(CLI::App* c, std::function<int()>& run);  // cli/GradCheckCmd.cpp
void addViewBench(CLI::App* c, std::function<int()>& run);       // cli/ViewCmd.cpp

}  // namespace sl::cli
