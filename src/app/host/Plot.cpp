#include "app/host/Plot.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include "core/Error.h"

extern char** environ;

namespace sl {

namespace fs = std::filesystem;

std::vector<fs::path> scriptDirs() {
    std::vector<fs::path> dirs;
    std::error_code ec;
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec && exe.has_parent_path()) {
        const fs::path up = exe.parent_path().parent_path();
        dirs.push_back(up / "scripts");
        dirs.push_back(up / "share" / "scratchlight" / "scripts");
    }
#ifdef SL_SCRIPTS_DIR
    dirs.emplace_back(SL_SCRIPTS_DIR);
#endif
    return dirs;
}

fs::path bundledDefaultScene() {
    const fs::path rel = fs::path("scenes") / "default" / "scene.json";
    std::error_code ec;
    for (const fs::path& d : scriptDirs())  // <root>/scripts: the scene is <root>/scenes/...
        if (fs::is_regular_file(d.parent_path() / rel, ec)) return d.parent_path() / rel;
    throw inputError("the bundled default scene (" + rel.string() + ")",
                     "was not found beside the executable nor in the source tree",
                     "pass a scene file");
}

fs::path findScript(const std::string& name) {
    std::error_code ec;
    for (const fs::path& d : scriptDirs())
        if (fs::is_regular_file(d / name, ec)) return d / name;
    return {};
}

std::string pythonInterpreter() {
    std::error_code ec;
    return fs::exists("/usr/bin/python3", ec) ? "/usr/bin/python3" : "python3";
}

std::string shellQuoted(const std::vector<std::string>& argv) {
    std::string line;
    for (const std::string& a : argv) {
        if (!line.empty()) line += ' ';
        const bool plain = !a.empty() && a.find_first_not_of(
                                             "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
                                             "0123456789_-+=./:,@%") == std::string::npos;
        if (plain) {
            line += a;
            continue;
        }
        line += '\'';
        for (char c : a) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
        line += '\'';
    }
    return line;
}

int runProcess(const std::vector<std::string>& argv) {
    if (argv.empty()) throw std::invalid_argument("runProcess: empty argument vector");
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = 0;
    const int err = posix_spawnp(&pid, args[0], nullptr, nullptr, args.data(), environ);
    if (err != 0) throw std::runtime_error("cannot start " + argv[0] + ": " + std::strerror(err));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR)
            throw std::system_error(errno, std::generic_category(), "waiting for " + argv[0]);
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return 1;
}

PlotOutcome runPlotScript(const std::string& script, const std::vector<std::string>& args,
                          bool run) {
    PlotOutcome o;
    std::error_code ec;
    fs::path path = fs::path(script).has_parent_path()
                        ? (fs::is_regular_file(script, ec) ? fs::path(script) : fs::path())
                        : findScript(script);
    o.command = {pythonInterpreter(), path.empty() ? script : path.string()};
    o.command.insert(o.command.end(), args.begin(), args.end());
    if (path.empty()) {
        std::string where;
        for (const fs::path& d : scriptDirs()) where += (where.empty() ? "" : ", ") + d.string();
        o.message = fs::path(script).has_parent_path() ? script + " not found"
                                                       : script + " not found in " + where;
        return o;
    }
    if (!run) return o;
    try {
        o.exitCode = runProcess(o.command);
    } catch (const std::runtime_error& e) {
        o.message = e.what();
        return o;
    }
    o.ran = true;
    return o;
}

}  // namespace sl
