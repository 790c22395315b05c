// Cooperative interruption (Ctrl-C, SIGTERM): one contract for every command. The command
// line's signal handler calls requestInterrupt(signal) (async-signal-safe: one lock-free atomic
// store); long loops poll interruptRequested() at safe points:
//   - tracing (precompute, render, judge), lamp fits, surface generation and the defect map
//     throw Interrupted at the next pixel, lamp or stage;
//   - optimizers stop at the next iteration through the optimize job's callback; the job then
//     throws Interrupted too, unless the user asked to keep the best E so far
//     (`optimize --keep-interrupted`: written marked "interrupted", app/jobs/OptimizeJob.h);
//   - a command that writes its results calls enterCommit() just before they appear (the
//     rename of a staged OUTDIR or of the output files): an interrupt before it throws, so
//     nothing is written and a previous OUTDIR stays as it was; one after it lets the writing
//     finish, and the command exits as if none had come (commandExitCode).
// The command line exits 128 + signal (130 for SIGINT, 143 for SIGTERM) when interrupted; a
// second signal exits at once, still removing staged and temporary outputs and killing external
// renderers' process groups (io/ExitCleanup.h).
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

namespace sl {

namespace detail {
inline std::atomic<int> gInterruptSignal{0};
inline std::atomic<bool> gCommitted{false};
static_assert(std::atomic<int>::is_always_lock_free);
}  // namespace detail

inline void requestInterrupt(int signal) noexcept {
    detail::gInterruptSignal.store(signal, std::memory_order_relaxed);
}
/// The signal handler's call: records `signal` and returns true when no interrupt was requested
/// yet; returns false, changing nothing, for a second one (async-signal-safe; of two signals
/// handled at once on two threads, exactly one is the first).
inline bool requestFirstInterrupt(int signal) noexcept {
    int expected = 0;
    return detail::gInterruptSignal.compare_exchange_strong(expected, signal,
                                                            std::memory_order_relaxed);
}
/// The signal that asked to stop, 0 if none.
inline int interruptSignal() noexcept {
    return detail::gInterruptSignal.load(std::memory_order_relaxed);
}
inline bool interruptRequested() noexcept {
    return interruptSignal() != 0;
}
/// Clears the request (tests; a long-lived process between jobs).
inline void clearInterrupt() noexcept {
    requestInterrupt(0);
    detail::gCommitted.store(false);
}

/// Thrown where work cannot stop with a usable result (tracing): nothing partial is kept.
struct Interrupted : std::runtime_error {
    Interrupted() : std::runtime_error("interrupted") {}
};

/// Throws Interrupted when an interrupt was requested.
inline void throwIfInterrupted() {
    if (interruptRequested()) throw Interrupted();
}

/// The last safe point of a command before its results appear: throws Interrupted when an
/// interrupt was requested (nothing is written); otherwise an interrupt from here on lets the
/// results be written whole, and the command's exit code stays its own (commandExitCode).
/// `evenIfInterrupted`: the results are written whatever came (what the user asked to keep).
inline void enterCommit(bool evenIfInterrupted = false) {
    if (!evenIfInterrupted) throwIfInterrupted();
    detail::gCommitted.store(true);
}

/// The exit code of a command whose work returned `rc`: 128 + signal when an interrupt was
/// requested before it entered its commit (enterCommit), else `rc`. A signal that arrives
/// between enterCommit's check and its store finds the results written whole: `rc` is right.
inline int commandExitCode(int rc) noexcept {
    if (!interruptRequested() || detail::gCommitted.load()) return rc;
    return 128 + interruptSignal();
}

}  // namespace sl
