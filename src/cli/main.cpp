// scratchlight: the command line, a thin shell over the library.
// Exit codes: 0 ok, 1 runtime error (bad input file, I/O, ...), 2 usage error.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "cli/Commands.h"
#include "cli/Common.h"
#include "cli/GradientCmds.h"
#include "cli/PaperCmds.h"
#include "core/Error.h"

int main(int argc, char** argv) {
    using namespace sl::cli;
    CLI::App app{
        "scratchlight: find the environment light under which the scratches and tool marks of a "
        "machined metal part show best."};
    app.require_subcommand(1);
    app.set_help_all_flag("--help-all", "Show the help of every command");

    std::function<int()> run;
    registerRender(app, run);
    registerGenSurface(app, run);
    registerTransport(app, run);
    registerJudge(app, run);
    registerBench(app, run);
    registerRace(app, run);
    registerGradients(app, run);
    registerPaper(app, run);

    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        app.exit(e);
        return kUsageError;
    } catch (const sl::InputError& e) {  // a value the library's parser refused (cli/Common.h)
        std::fprintf(stderr, "error: %s\n", withFlags(app, e.what()).c_str());
        return kRuntimeError;
    }
    try {
        return run ? run() : kUsageError;
    } catch (const UsageError& e) {
        std::fprintf(stderr, "error: %s (see --help)\n", e.what());
        return kUsageError;
    } catch (const std::exception& e) {  // InputError and every other failure
        std::fprintf(stderr, "error: %s\n", withFlags(app, e.what()).c_str());
        return kRuntimeError;
    }
}
