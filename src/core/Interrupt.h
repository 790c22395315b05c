// Cooperative interruption (Ctrl-C, SIGTERM). The command line's signal handler calls
// requestInterrupt(signal) (async-signal-safe: one lock-free atomic store); long loops poll
// interruptRequested() at safe points:
//   - optimizers stop at the next iteration through the optimize job's callback, which then
//     writes the best E so far marked "interrupted" (app/OptimizeJob.h);
//   - tracing (precompute, render) throws Interrupted at the next tile, so nothing partial is
//     written (every output is staged or written under a temporary name).
// The command line exits 128 + signal (130 for SIGINT, 143 for SIGTERM); a second signal exits
// at once.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>

namespace sl {

namespace detail {
inline std::atomic<int> gInterruptSignal{0};
static_assert(std::atomic<int>::is_always_lock_free);
}  // namespace detail

inline void requestInterrupt(int signal) noexcept {
    detail::gInterruptSignal.store(signal, std::memory_order_relaxed);
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
}

/// Thrown where work cannot stop with a usable result (tracing): nothing partial is kept.
struct Interrupted : std::runtime_error {
    Interrupted() : std::runtime_error("interrupted") {}
};

/// Throws Interrupted when an interrupt was requested.
inline void throwIfInterrupted() {
    if (interruptRequested()) throw Interrupted();
}

}  // namespace sl
