// Each command registers its CLI11 subcommand and, when chosen, sets `run`.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace sl::cli {

void registerRender(CLI::App& app, std::function<int()>& run);
void registerGenSurface(CLI::App& app, std::function<int()>& run);
void registerBench(CLI::App& app, std::function<int()>& run);
void registerTransport(CLI::App& app, std::function<int()>& run);
void registerJudge(CLI::App& app, std::function<int()>& run);
void registerRace(CLI::App& app, std::function<int()>& run);  // after registerBench
void registerDefectMap(CLI::App& app, std::function<int()>& run);
void registerInsertDefects(CLI::App& app, std::function<int()>& run);
void registerCache(CLI::App& app, std::function<int()>& run);
void registerLamps(CLI::App& app, std::function<int()>& run);
void registerView(CLI::App& app, std::function<int()>& run);  // after registerBench

}  // namespace sl::cli
