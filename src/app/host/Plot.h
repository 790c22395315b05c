// Running the plotting scripts (scripts/plot_*.py) from a command: the script is found beside
// the executable, not relative to the current directory, and python3 is started with an
// argument vector (posix_spawn), never through a shell, so no path needs quoting.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace sl {

/// The folders searched for a script, in order: <exe dir>/../scripts (the build directory in
/// the source tree), <exe dir>/../share/scratchlight/scripts (installed), then the source
/// tree's scripts/ recorded at configure time.
std::vector<std::filesystem::path> scriptDirs();

/// The bundled default scene (scenes/default/scene.json), found like the scripts: beside the
/// executable's folder (the source tree), under share/scratchlight (installed), then in the
/// source tree recorded at configure time; so a default works from any directory. Throws
/// InputError when none exists.
std::filesystem::path bundledDefaultScene();

/// The first scriptDirs()/name that exists; empty if none does.
std::filesystem::path findScript(const std::string& name);

/// /usr/bin/python3 (Debian's, which has python3-matplotlib) when it exists, else "python3"
/// looked up on PATH.
std::string pythonInterpreter();

/// The argument vector as one line a shell would accept (for messages such as "plot with: ...").
std::string shellQuoted(const std::vector<std::string>& argv);

/// Starts argv[0] (looked up on PATH when it has no '/') with argv, waits for it, and returns
/// its exit status (128 + signal number when a signal ended it). Throws std::runtime_error when
/// it cannot be started.
int runProcess(const std::vector<std::string>& argv);

struct PlotOutcome {
    bool ran = false;  // false: script or interpreter missing (see message)
    int exitCode = 0;
    std::vector<std::string> command;  // interpreter, script, arguments
    std::string message;               // why it did not run
};

/// Runs `python3 <script> args...`: a bare name ("plot_noise.py") is found by findScript, a path
/// is used as given. With run = false it only fills command (for a "plot with:" hint). Does not
/// throw: a missing script or interpreter leaves ran false with a message; check exitCode.
PlotOutcome runPlotScript(const std::string& script, const std::vector<std::string>& args,
                          bool run = true);

}  // namespace sl
