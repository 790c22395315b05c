// The paper's tools on the command line:
//   scratchlight scratchmap (HEIGHTMAP | SCENE.json) [--kernel K] [--patch P] [--threshold T]
//                           [-o map.png] [--image-output MASK.png]
//   scratchlight envmap-preset [studio] [--width 50 --height 25] [-o studio.exr]
//   scratchlight report (OUTDIR... | --spec FIGURES.json) [-o report.html] [--title T]
//                       [--note TEXT]... [--combined-loss]
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace sl::cli {

void registerPaper(CLI::App& app, std::function<int()>& run);

}  // namespace sl::cli
