// Wall-clock seconds since a start (std::chrono::steady_clock), for timings in summaries and
// benchmark tables; and the process's CPU seconds (all threads, std::clock), which a benchmark
// reports beside wall time when other work shares the machine.
#pragma once

#include <chrono>
#include <ctime>

namespace sl {

class Stopwatch {
  public:
    Stopwatch() : start_(Clock::now()) {}
    /// Seconds since construction or the last restart().
    double seconds() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }
    void restart() { start_ = Clock::now(); }

  private:
    using Clock = std::chrono::steady_clock;
    Clock::time_point start_;
};

/// CPU seconds the whole process (every thread) used since construction.
class CpuStopwatch {
  public:
    CpuStopwatch() : start_(std::clock()) {}
    double seconds() const { return double(std::clock() - start_) / CLOCKS_PER_SEC; }

  private:
    std::clock_t start_;
};

/// Seconds one call of f takes.
template <typename F>
double timeSeconds(F&& f) {
    const Stopwatch w;
    f();
    return w.seconds();
}

}  // namespace sl
