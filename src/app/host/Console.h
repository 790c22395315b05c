// Console: how a command shows the library's progress (core/Progress.h) and log lines.
//
//   terminal (stderr is a TTY): one line redrawn in place, at most 10 times a second,
//       precompute [#########...........]  45%  6.1 s, ETA 7.4 s
//     (an unknown total shows the elapsed time only); the finished task's line stays, ending
//     "done in 13.5 s". A log line clears the bar, is printed, and the bar is redrawn.
//   piped (not a TTY: `| tee log`, CI): a plain line per running task every `plainEvery`
//     seconds, "precompute: 45% (6.1 s, ETA 7.4 s)", and "precompute: done in 13.5 s".
// A task appears only once it has run `showAfter` seconds (terminal) or `plainEvery` seconds
// (piped), so short steps stay silent; nested tasks show the innermost. A ticker thread
// redraws, so a step with no reports (loading, a BVH build) still shows its elapsed time.
//
// Log lines (spdlog, the library's logger): info to stdout as the bare message, warnings and
// errors to stderr prefixed "warning: " / "error: ", debug (shown with -v) prefixed "debug: ".
#pragma once

#include <condition_variable>
#include <cstdio>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/Progress.h"
#include "core/Stopwatch.h"

namespace spdlog::sinks {
class sink;
}

namespace sl {

struct ConsoleOptions {
    bool terminal = false;         // redraw a bar in place (else plain lines)
    double plainEvery = 5.0;       // piped: seconds between a task's lines
    double showAfter = 0.5;        // terminal: a task is drawn once it has run this long
    int width = 0;                 // terminal columns (0: ask the terminal, else 80)
    std::FILE* progress = stderr;  // where progress goes
    std::FILE* info = stdout;      // where info and debug log lines go
    std::FILE* warnings = stderr;  // where warnings and errors go
};

/// "0.4 s", "12 s", "3 min 05 s", "1 h 02 min".
std::string formatDuration(double seconds);

/// One task's status line without the terminal's bar: "45% (120/241), 6.1 s, ETA 7.4 s, loss
/// 7.7" (total 0: "6.1 s"; the detail last, where a narrow terminal cuts it). The ETA is shown
/// once 1 % of the work or 1 s has passed.
std::string formatProgress(double done, double total, const std::string& detail, double seconds);

class Console final : public ProgressListener {
  public:
    explicit Console(ConsoleOptions options);
    ~Console() override;
    Console(const Console&) = delete;
    Console& operator=(const Console&) = delete;

    void started(long id, const std::string& label, double total) override;
    void advanced(long id, double done, double total) override;
    void detailed(long id, const std::string& detail) override;
    void finished(long id, bool completed) override;

    /// Prints one line (no trailing newline needed) without tearing a drawn bar.
    void line(std::FILE* stream, const std::string& text);

    /// A spdlog sink that prints through line() (install with spdlog::default_logger()).
    std::shared_ptr<spdlog::sinks::sink> logSink();

  private:
    struct Task {
        long id;
        std::string label, detail;
        double done = 0, total = 0;
        Stopwatch clock;
        double lastPrinted = 0;  // piped: clock seconds of the last line
        bool shown = false;
    };
    void tick();          // under mutex_
    void draw(Task& t);   // under mutex_: terminal bar
    void clearBar();      // under mutex_
    Task* find(long id);  // under mutex_
    int columns() const;

    ConsoleOptions o_;
    std::mutex mutex_;
    std::condition_variable wake_;
    std::vector<Task> tasks_;  // start order; the last is drawn
    bool barDrawn_ = false;    // a bar occupies the current terminal line
    bool stop_ = false;
    std::thread ticker_;
};

}  // namespace sl
