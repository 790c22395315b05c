// Each command registers its CLI11 subcommand and, when chosen, sets `run`; each is defined in
// the file named after it (cli/XCmd.cpp), and main.cpp calls them in `--help`'s order.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace sl::cli {

void registerRender(CLI::App& app, std::function<int()>& run);
void registerGenSurface(CLI::App& app, std::function<int()>& run);
void registerInsertDefects(CLI::App& app, std::function<int()>& run);
void registerPrecompute(CLI::App& app, std::function<int()>& run);
void registerRelight(CLI::App& app, std::function<int()>& run);
void registerOptimize(CLI::App& app, std::function<int()>& run);
void registerJudge(CLI::App& app, std::function<int()>& run);
void registerBench(CLI::App& app, std::function<int()>& run);
// after registerBench (each adds to `bench`):
void registerRace(CLI::App& app, std::function<int()>& run);
void registerGradCheck(CLI::App& app, std::function<int()>& run);
void registerExportMitsuba(CLI::App& app, std::function<int()>& run);
void registerScratchMap(CLI::App& app, std::function<int()>& run);
void registerReport(CLI::App& app, std::function<int()>& run);
void registerEnvMapPreset(CLI::App& app, std::function<int()>& run);
void registerDefectMap(CLI::App& app, std::function<int()>& run);
void registerCache(CLI::App& app, std::function<int()>& run);
void registerLamps(CLI::App& app, std::function<int()>& run);
void registerView(CLI::App& app, std::function<int()>& run);  // after registerBench

}  // namespace sl::cli
