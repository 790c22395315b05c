// scratchlight: the command line, a thin shell over the library.
// Exit codes: 0 ok, 1 runtime error (bad input file, I/O, ...), 2 usage error, 128 + signal
// when interrupted (130 Ctrl-C, 143 SIGTERM; core/Interrupt.h says what is kept).
#include <signal.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include "app/host/Console.h"
#include "app/host/Mpi.h"
#include "app/host/Version.h"
#include "cli/Commands.h"
#include "cli/Common.h"
#include "core/Error.h"
#include "core/Interrupt.h"
#include "core/Text.h"
#include "io/ExitCleanup.h"

namespace {

/// The first SIGINT/SIGTERM asks the work to stop at its next safe point; a second one exits at
/// once, removing staged and temporary outputs and killing external renderers first
/// (io/ExitCleanup.h). Only async-signal-safe calls here.
extern "C" void onSignal(int signal) {
    if (!sl::requestFirstInterrupt(signal)) sl::exitAtOnce(128 + signal);
    static const char msg[] =
        "\ninterrupted: stopping at the next safe point (again to quit at once)\n";
    [[maybe_unused]] const ssize_t n = ::write(STDERR_FILENO, msg, sizeof msg - 1);
}

void installSignalHandlers() {
    struct sigaction sa {};
    sa.sa_handler = onSignal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART;
    sigaction(SIGINT, &sa, nullptr);
    sigaction(SIGTERM, &sa, nullptr);
    // A file-size limit (ulimit -f) makes the write fail with EFBIG, reported as an error with
    // the file's name, instead of killing the process halfway.
    signal(SIGXFSZ, SIG_IGN);
}

/// An unknown command word gets its name, the nearest command and the list, not CLI11's "A
/// subcommand is required". Returns false when `word` is a command.
bool reportUnknownCommand(const CLI::App& app, const std::string& word) {
    std::string names;
    std::vector<std::string> commands;
    for (const CLI::App* c : app.get_subcommands({})) {
        if (c->get_name() == word) return false;
        names += names.empty() ? "" : ", ";
        names += c->get_name();
        commands.push_back(c->get_name());
    }
    std::fprintf(stderr, "error: unknown command '%s'", word.c_str());
    const std::string nearest = sl::nearestName(word, commands);
    if (!nearest.empty()) std::fprintf(stderr, "; did you mean '%s'?", nearest.c_str());
    std::fprintf(stderr, "\ncommands: %s (scratchlight --help)\n", names.c_str());
    return true;
}

/// After a parse error: every "--name" on the command line that no chosen command (or the app)
/// has gets "did you mean --nearest?" from the options of the command that was chosen.
void suggestOptions(const CLI::App& app, int argc, char** argv) {
    std::vector<const CLI::App*> chain{&app};
    for (const CLI::App* c = &app;;) {
        const auto chosen = c->get_subcommands();
        if (chosen.empty()) break;
        c = chosen.front();
        chain.push_back(c);
    }
    std::vector<std::string> known;
    for (const CLI::App* c : chain)
        for (const CLI::Option* o : c->get_options())
            for (const std::string& n : o->get_lnames()) known.push_back("--" + n);
    for (int k = 1; k < argc; ++k) {
        std::string word = argv[k];
        if (word == "--") break;
        if (word.rfind("--", 0) != 0) continue;
        word = word.substr(0, word.find('='));
        if (std::find(known.begin(), known.end(), word) != known.end()) continue;
        const std::string nearest = sl::nearestName(word, known);
        if (!nearest.empty())
            std::fprintf(stderr, "%s: did you mean %s?\n", word.c_str(), nearest.c_str());
    }
}

/// CLI11 drops the empty entries of a comma-separated list ("--starts a,,b" read as a,b; issue
/// 35): after the parse, every value given to a list option of the chosen commands is checked
/// for one. Returns the message, or "" when every list is whole.
std::string emptyListEntry(const CLI::App& app, int argc, char** argv) {
    std::vector<const CLI::Option*> lists;
    for (const CLI::App* c = &app;;) {
        for (const CLI::Option* o : c->get_options())
            if (o->get_delimiter() == ',' && o->count() > 0) lists.push_back(o);
        const auto chosen = c->get_subcommands();
        if (chosen.empty()) break;
        c = chosen.front();
    }
    for (int k = 1; k < argc; ++k) {
        const std::string word = argv[k];
        if (word == "--") break;
        for (const CLI::Option* o : lists)
            for (const std::string& n : o->get_lnames()) {
                const std::string flag = "--" + n;
                std::string value;
                if (word.rfind(flag + "=", 0) == 0)
                    value = word.substr(flag.size() + 1);
                else if (word == flag && k + 1 < argc)
                    value = argv[k + 1];
                else
                    continue;
                if (value.empty() || value.front() == ',' || value.back() == ',' ||
                    value.find(",,") != std::string::npos)
                    return flag + ": '" + value +
                           "': an empty entry; give the entries separated by single commas";
            }
    }
    return "";
}

}  // namespace

int main(int argc, char** argv) {
    using namespace sl::cli;
    installSignalHandlers();  // first: a Ctrl-C during start-up is already cooperative
    for (int k = 0; k < argc; ++k) {
        if (k) invokedCommandLine() += ' ';
        invokedCommandLine() += argv[k];
    }
    CLI::App app{
        "scratchlight: find the environment light under which the scratches and tool marks of a "
        "machined metal part show best."};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Show the help of every command");
    app.set_version_flag("--version", sl::versionText(),
                         "Print the version, its commit and the libraries' versions");
    // How a command talks (app/host/Console.h); given before or after the command's name.
    bool quiet = false;
    int verbose = 0;
    double progressEvery = sl::ConsoleOptions{}.plainEvery;
    app.fallthrough();
    app.add_flag("-q,--quiet", quiet,
                 "Only results, warnings and errors: no progress, no context lines");
    app.add_flag("-v,--verbose", verbose, "Also debug lines (e.g. every optimizer iteration)");
    app.add_option("--progress-every", progressEvery,
                   "Seconds between progress lines when the output is not a terminal")
        ->check(positiveNumber())
        ->capture_default_str();

    std::function<int()> run;
    registerRender(app, run);
    registerGenSurface(app, run);
    registerInsertDefects(app, run);
    registerPrecompute(app, run);
    registerRelight(app, run);
    registerOptimize(app, run);
    registerJudge(app, run);
    registerBench(app, run);
    registerGradCheck(app, run);
    registerExportMitsuba(app, run);
    registerScratchMap(app, run);
    registerReport(app, run);
    registerEnvMapPreset(app, run);
    registerDefectMap(app, run);
    registerCache(app, run);
    registerLamps(app, run);
    registerView(app, run);
    registerInfo(app, run);

    if (argc > 1 && argv[1][0] != '-' && reportUnknownCommand(app, argv[1])) return kUsageError;
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        suggestOptions(app, argc, argv);
        return kUsageError;
    } catch (const sl::InputError& e) {  // a value the library's parser refused (cli/Common.h)
        std::fprintf(stderr, "error: %s\n", withFlags(app, e.what()).c_str());
        return kRuntimeError;
    }
    if (const std::string empty = emptyListEntry(app, argc, argv); !empty.empty()) {
        std::fprintf(stderr, "error: %s\n", empty.c_str());
        return kUsageError;
    }
    // MPI ranks (app/host/Mpi.h, docs/CLUSTER.md): only optimize runs over several; the ranks but
    // rank 0 print only errors, and an error on any rank ends them all.
    std::unique_ptr<sl::Communicator> world;
    try {
        world = sl::worldCommunicator();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return kRuntimeError;
    }
    worldRanks() = world.get();
    const auto chosen = app.get_subcommands();
    if (world->distributed() && (chosen.empty() || chosen.front()->get_name() != "optimize")) {
        if (world->root())
            std::fprintf(stderr,
                         "error: only `optimize` runs over MPI ranks (this is %s over %d); run "
                         "the command as one process\n",
                         chosen.empty() ? "no command" : chosen.front()->get_name().c_str(),
                         world->size());
        world->abort(kUsageError);
    }
    if (!world->root()) quiet = true;
    // Output: progress and log lines through one console (app/host/Console.h). Lines, not blocks,
    // reach a pipe as they are printed (`| tee log` shows the run as it goes).
    std::setvbuf(stdout, nullptr, _IOLBF, 0);
    sl::ConsoleOptions co;
    co.terminal = ::isatty(STDERR_FILENO) != 0;
    co.plainEvery = progressEvery;
    sl::Console console(co);
    spdlog::default_logger()->sinks() = {console.logSink()};
    spdlog::set_level(!world->root() ? spdlog::level::err
                      : quiet        ? spdlog::level::warn
                      : verbose > 0  ? spdlog::level::debug
                                     : spdlog::level::info);
    struct ListenerScope {
        explicit ListenerScope(sl::ProgressListener* l) { sl::setProgressListener(l); }
        ~ListenerScope() {
            sl::setProgressListener(nullptr);
            spdlog::default_logger()->sinks().clear();
        }
    } listenerScope(quiet ? nullptr : &console);
    // An error on one rank of several: its message, then every rank ends (MPI_Abort).
    auto fail = [&world](int code) {
        if (world->distributed()) world->abort(code);
        return code;
    };
    auto rankPrefix = [&world] {
        return world->distributed() ? "rank " + std::to_string(world->rank()) + " of " +
                                          std::to_string(world->size()) + ": "
                                    : std::string();
    };
    try {
        const int rc = run ? run() : kUsageError;
        if (sl::interruptRequested() && sl::commandExitCode(rc) == rc && rc == kOk)
            std::fprintf(stderr, "interrupted after the results were complete: kept\n");
        return sl::commandExitCode(rc);
    } catch (const sl::Interrupted&) {
        std::fprintf(stderr, "interrupted: nothing was written (a previous output is unchanged)\n");
        return fail(128 + sl::interruptSignal());
    } catch (const std::bad_alloc&) {
        const size_t n = gFailedAllocationBytes.load();
        const double gb = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) *
                          static_cast<double>(::sysconf(_SC_PAGE_SIZE)) / 1e9;
        std::fprintf(stderr,
                     "error: out of memory: an allocation of %.3g GB failed (this machine has "
                     "%.3g GB); use a smaller image (camera width/height), fewer spp, or a "
                     "smaller height map\n",
                     static_cast<double>(n) / 1e9, gb);
        return fail(kRuntimeError);
    } catch (const UsageError& e) {
        std::fprintf(stderr, "error: %s%s (see --help)\n", rankPrefix().c_str(), e.what());
        return fail(kUsageError);
    } catch (const std::exception& e) {  // InputError and every other failure
        std::fprintf(stderr, "error: %s%s\n", rankPrefix().c_str(),
                     withFlags(app, e.what()).c_str());
        return fail(kRuntimeError);
    }
}
