// Wall-clock seconds since a start (std::chrono::steady_clock), for timings in summaries and
// benchmark tables.
#pragma once

#include <chrono>

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

/// Seconds one call of f takes.
template <typename F>
double timeSeconds(F&& f) {
    const Stopwatch w;
    f();
    return w.seconds();
}

}  // namespace sl
