#include "core/Progress.h"

#include <exception>

#include "core/Interrupt.h"

namespace sl {

namespace {
std::atomic<ProgressListener*> gListener{nullptr};
std::atomic<long> gNextId{1};
}  // namespace

void setProgressListener(ProgressListener* listener) {
    gListener.store(listener);
}

ProgressListener* progressListener() {
    return gListener.load();
}

ProgressTask::ProgressTask(std::string label, double total)
    : id_(gNextId.fetch_add(1)),
      listener_(gListener.load()),
      total_(total > 0 ? total : 0),
      uncaught_(std::uncaught_exceptions()) {
    if (listener_) listener_->started(id_, label, total_.load());
}

ProgressTask::~ProgressTask() {
    if (!listener_) return;
    listener_->finished(id_, std::uncaught_exceptions() == uncaught_ && !interruptRequested());
}

void ProgressTask::set(double done) {
    done_.store(done, std::memory_order_relaxed);
    if (listener_) listener_->advanced(id_, done, total_.load(std::memory_order_relaxed));
}

void ProgressTask::advance(double n) {
    double d = done_.load(std::memory_order_relaxed);
    while (!done_.compare_exchange_weak(d, d + n, std::memory_order_relaxed)) {
    }
    if (listener_) listener_->advanced(id_, d + n, total_.load(std::memory_order_relaxed));
}

void ProgressTask::setTotal(double total) {
    total_.store(total > 0 ? total : 0, std::memory_order_relaxed);
    if (listener_) listener_->advanced(id_, done_.load(), total_.load());
}

void ProgressTask::detail(const std::string& text) {
    if (listener_) listener_->detailed(id_, text);
}

std::function<void(double)> ProgressTask::fraction() {
    if (total() <= 0) setTotal(1);
    return [this](double f) { set(f * total()); };
}

}  // namespace sl
