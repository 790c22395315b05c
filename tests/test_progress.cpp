// Progress (core/Progress.h) and how the console shows it (app/host/Console.h): the status text,
// the terminal bar and its tearing-free log lines, the piped plain lines, and the command line
// printing progress live when piped.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <thread>

#include "TestUtil.h"
#include "app/host/Console.h"
#include "core/Progress.h"

using namespace sl;

namespace {

/// What a FILE* opened with tmpfile() holds.
std::string contents(std::FILE* f) {
    std::fflush(f);
    std::rewind(f);
    std::string s;
    char buf[4096];
    for (size_t n; (n = std::fread(buf, 1, sizeof buf, f)) > 0;) s.append(buf, n);
    return s;
}

size_t count(const std::string& s, const std::string& what) {
    size_t n = 0;
    for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
}

/// Installs `listener` for a scope.
struct Listening {
    explicit Listening(ProgressListener* l) { setProgressListener(l); }
    ~Listening() { setProgressListener(nullptr); }
};

void sleepMs(int ms) {
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
}

/// What a console with options `o` prints (every stream to one temporary file) while `body`
/// runs with it as the progress listener.
template <class Body>
std::string printed(ConsoleOptions o, Body&& body) {
    std::FILE* out = std::tmpfile();
    if (!out) return "tmpfile failed";
    o.progress = o.info = o.warnings = out;
    {
        Console console(o);
        Listening l(&console);
        body(console, out);
    }
    const std::string s = contents(out);
    std::fclose(out);
    return s;
}

ConsoleOptions piped(double every) {
    ConsoleOptions o;
    o.terminal = false;
    o.plainEvery = every;
    return o;
}

}  // namespace

TEST(Progress, DurationsReadAsAPersonWrites) {
    EXPECT_EQ(formatDuration(0.04), "0.0 s");
    EXPECT_EQ(formatDuration(6.14), "6.1 s");
    EXPECT_EQ(formatDuration(12.4), "12 s");
    EXPECT_EQ(formatDuration(185), "3 min 05 s");
    EXPECT_EQ(formatDuration(3720), "1 h 02 min");
    EXPECT_EQ(formatDuration(-1), "0.0 s");
}

TEST(Progress, StatusHasPercentCountsElapsedEtaAndDetail) {
    // 120 of 240 in 6 s: 6 s to go.
    EXPECT_EQ(formatProgress(120, 240, "loss 7.7", 6.0),
              "50% (120/240), 6.0 s, ETA 6.0 s, loss 7.7");
    // A fraction (total 1) has no counts.
    EXPECT_EQ(formatProgress(0.25, 1, "", 2.0), "25%, 2.0 s, ETA 6.0 s");
    // Unknown total: elapsed time only.
    EXPECT_EQ(formatProgress(3, 0, "", 2.5), "2.5 s");
    // No ETA before 1 % or 1 s of evidence, none when done.
    EXPECT_EQ(formatProgress(0.001, 1, "", 0.2), "0%, 0.2 s");
    EXPECT_EQ(formatProgress(1, 1, "", 3.0), "100%, 3.0 s");
}

TEST(Progress, WithoutAListenerATaskIsSilent) {
    setProgressListener(nullptr);
    ProgressTask t("nothing", 10);
    t.advance(3);
    t.detail("x");
    EXPECT_EQ(t.done(), 3);
    auto f = t.fraction();
    f(0.5);
    EXPECT_EQ(t.done(), 5);
}

TEST(Progress, PipedPrintsPlainLinesEveryIntervalAndTheEnd) {
    const ConsoleOptions o = piped(0.15);
    const std::string s = printed(o, [&](Console&, std::FILE*) {
        {
            ProgressTask quick("quick", 1);  // shorter than the interval: never shown
            quick.set(1);
        }
        ProgressTask t("tracing", 100);
        for (int k = 0; k < 10; ++k) {
            t.advance(10);
            sleepMs(60);
        }
    });
    EXPECT_EQ(count(s, "quick"), 0u) << s;
    EXPECT_GE(count(s, "tracing: "), 3u) << s;  // ~0.6 s at 0.15 s: a few lines, then the end
    EXPECT_NE(s.find("ETA"), std::string::npos) << s;
    EXPECT_NE(s.find("tracing: done in"), std::string::npos) << s;
    EXPECT_EQ(s.find('\r'), std::string::npos) << "no terminal control when piped";
}

TEST(Progress, TerminalBarFitsTheWidthAndLogLinesDoNotTearIt) {
    ConsoleOptions o;
    o.terminal = true;
    o.showAfter = 0;
    o.width = 60;
    const std::string s = printed(o, [&](Console& console, std::FILE* out) {
        ProgressTask t("a rather long label for a narrow terminal", 1000);
        t.detail("loss 1.234567, held out 2.345678");
        for (int k = 0; k < 5; ++k) {
            t.advance(100);
            sleepMs(120);
        }
        console.line(out, "a log line");
        sleepMs(150);
    });
    EXPECT_NE(s.find('['), std::string::npos) << s;
    // Every drawn bar (between a \r and the erase-to-end) fits in 59 columns.
    for (size_t at = s.find('\r'); at != std::string::npos; at = s.find('\r', at + 1)) {
        const size_t end = s.find("\033[K", at);
        ASSERT_NE(end, std::string::npos);
        EXPECT_LE(end - at - 1, 59u) << s.substr(at, end - at);
    }
    // The log line is printed on a cleared line, on its own.
    EXPECT_NE(s.find("\r\033[Ka log line\n"), std::string::npos) << s;
    EXPECT_NE(s.find(": done in"), std::string::npos) << s;
}

TEST(Progress, ATaskEndedByAnExceptionSaysStopped) {
    const ConsoleOptions o = piped(0.05);
    const std::string s = printed(o, [&](Console&, std::FILE*) {
        try {
            ProgressTask t("failing", 10);
            t.advance(4);
            sleepMs(200);
            throw std::runtime_error("bad input");
        } catch (const std::runtime_error&) {
        }
    });
    EXPECT_NE(s.find("failing: stopped at 40% after"), std::string::npos) << s;
}

TEST(Progress, NestedTasksShowTheInnermostThenResume) {
    const ConsoleOptions o = piped(0.1);
    const std::string s = printed(o, [&](Console&, std::FILE*) {
        ProgressTask outer("outer", 2);
        {
            ProgressTask inner("inner", 1);
            sleepMs(250);
            inner.set(1);
        }
        outer.advance(2);
    });
    EXPECT_NE(s.find("inner: "), std::string::npos) << s;
    EXPECT_NE(s.find("inner: done in"), std::string::npos) << s;
    EXPECT_LT(s.find("inner: done in"), s.find("outer: done in")) << s;
}

// The command line, piped (as `| tee log` or CI): progress lines with an ETA arrive while the
// work runs, not at its end; -q silences them.
TEST(Progress, CommandLineShowsProgressLiveWhenPiped) {
    test::TempDir dir("progress");
    const std::string scene = std::string(SL_SOURCE_DIR) + "/scenes/default/scene.json";
    const std::string cmd = std::string(SL_CLI_PATH) + " precompute " + scene +
                            " --spp 48 --progress-every 0.2 -o " + (dir / "p.tm").string() +
                            " 2>&1";
    using Clock = std::chrono::steady_clock;
    FILE* f = popen(cmd.c_str(), "r");
    ASSERT_NE(f, nullptr);
    std::string all;
    double firstEta = -1;
    const auto start = Clock::now();
    char line[4096];
    while (std::fgets(line, sizeof line, f)) {
        all += line;
        if (firstEta < 0 && std::string(line).find("ETA") != std::string::npos)
            firstEta = std::chrono::duration<double>(Clock::now() - start).count();
    }
    const double end = std::chrono::duration<double>(Clock::now() - start).count();
    ASSERT_EQ(pclose(f), 0) << all;
    ASSERT_GE(firstEta, 0) << all;
    EXPECT_GT(end - firstEta, 0.1) << "the progress line came only at the end\n" << all;
    EXPECT_NE(all.find("precompute (512x512 px, 48 spp): done in"), std::string::npos) << all;

    const auto quiet = test::runCli("-q precompute " + scene +
                                    " --spp 48 --progress-every 0.2 -o " + (dir / "q.tm").string());
    ASSERT_EQ(quiet.exitCode, 0) << quiet.output;
    EXPECT_EQ(quiet.output.find("ETA"), std::string::npos) << quiet.output;
    EXPECT_NE(quiet.output.find("wrote"), std::string::npos) << quiet.output;
}
