// Gradient validation and the cross-renderer export:
//   scratchlight gradcheck SCENE.json [--methods exact,autodiff,fd,spsa] [-o REPORT.json] ...
//   scratchlight bench gradients [SCENE.json] [-o DIR] ...
//   scratchlight export-mitsuba SCENE.json [--envmap SPEC | --lamps lamps.json] [-o OUTDIR]
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace sl::cli {

/// Registers `gradcheck`, `export-mitsuba` and `bench gradients`. Call it after registerBench:
/// `gradients` is added to the existing `bench` subcommand (created here if it does not exist).
void registerGradients(CLI::App& app, std::function<int()>& run);

}  // namespace sl::cli
