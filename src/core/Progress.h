// Progress of long steps. The library says what it is doing: a ProgressTask names a step
// (label), how much of it is done and of how much (total; 0 = unknown, only time is shown) and
// an optional detail (e.g. the current loss). Whoever runs the library decides how to show it:
// the command line installs a ProgressListener (app/host/Console.h: a bar with elapsed time and ETA
// on a terminal, a plain line every few seconds when piped). With no listener (tests, library
// use) a task costs one atomic load per call.
//
// Tasks nest (a held-out estimate inside optimize): a listener sees them in start order and
// shows the innermost. A task is finished when it goes out of scope: completed, unless an
// exception is unwinding through it or an interrupt was requested (core/Interrupt.h); a step
// that ends before its total on purpose (a converged optimizer) is completed.
//
// Threads: set/advance/detail may be called from any thread; the listener serialises.
#pragma once

#include <atomic>
#include <functional>
#include <string>

namespace sl {

class ProgressListener {
  public:
    virtual ~ProgressListener() = default;
    /// id: unique per task in this process; total 0: unknown.
    virtual void started(long id, const std::string& label, double total) = 0;
    virtual void advanced(long id, double done, double total) = 0;
    virtual void detailed(long id, const std::string& detail) = 0;
    virtual void finished(long id, bool completed) = 0;
};

/// The process's listener (nullptr: none). The caller keeps it alive until it is reset.
void setProgressListener(ProgressListener* listener);
ProgressListener* progressListener();

class ProgressTask {
  public:
    explicit ProgressTask(std::string label, double total = 0);
    ~ProgressTask();
    ProgressTask(const ProgressTask&) = delete;
    ProgressTask& operator=(const ProgressTask&) = delete;

    void set(double done);
    void advance(double n = 1);
    /// A new total (e.g. once a budget is known); keeps done.
    void setTotal(double total);
    void detail(const std::string& text);
    /// A callback for code that reports a fraction in [0, 1] (render/PathTracer.h).
    std::function<void(double)> fraction();

    double total() const { return total_.load(std::memory_order_relaxed); }
    double done() const { return done_.load(std::memory_order_relaxed); }

  private:
    long id_;
    ProgressListener* listener_;  // captured at start: the task reports to one listener
    std::atomic<double> done_{0}, total_{0};
    int uncaught_;  // std::uncaught_exceptions() at the start
};

}  // namespace sl
