#include "app/host/Console.h"

#include <spdlog/sinks/base_sink.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace sl {

std::string formatDuration(double seconds) {
    char buf[64];
    if (!(seconds >= 0)) seconds = 0;
    if (seconds < 9.95) {
        std::snprintf(buf, sizeof buf, "%.1f s", seconds);
    } else if (seconds < 59.5) {
        std::snprintf(buf, sizeof buf, "%.0f s", seconds);
    } else if (seconds < 3599.5) {
        const long s = std::lround(seconds);
        std::snprintf(buf, sizeof buf, "%ld min %02ld s", s / 60, s % 60);
    } else {
        const long m = std::lround(seconds / 60);
        std::snprintf(buf, sizeof buf, "%ld h %02ld min", m / 60, m % 60);
    }
    return buf;
}

std::string formatProgress(double done, double total, const std::string& detail, double seconds) {
    std::string s;
    if (total > 0) {
        const double f = std::clamp(done / total, 0.0, 1.0);
        s = std::to_string(static_cast<int>(std::floor(100.0 * f))) + "%";
        if (total > 1 && total == std::floor(total))
            s += " (" + std::to_string(static_cast<long long>(std::min(done, total))) + "/" +
                 std::to_string(static_cast<long long>(total)) + ")";
    }
    s += (s.empty() ? "" : ", ") + formatDuration(seconds);
    if (total > 0 && done > 0 && done < total && (done >= 0.01 * total || seconds >= 1.0))
        s += ", ETA " + formatDuration(seconds * (total - done) / done);
    if (!detail.empty()) s += ", " + detail;
    return s;
}

namespace {

class ConsoleLogSink final : public spdlog::sinks::base_sink<std::mutex> {
  public:
    ConsoleLogSink(Console& console, std::FILE* info, std::FILE* warnings)
        : console_(console), info_(info), warnings_(warnings) {}

  protected:
    void sink_it_(const spdlog::details::log_msg& msg) override {
        std::string text(msg.payload.data(), msg.payload.size());
        std::FILE* stream = info_;
        switch (msg.level) {
            case spdlog::level::trace:
            case spdlog::level::debug:
                text = "debug: " + text;
                break;
            case spdlog::level::info:
                break;
            case spdlog::level::warn:
                text = "warning: " + text;
                stream = warnings_;
                break;
            default:
                text = "error: " + text;
                stream = warnings_;
                break;
        }
        console_.line(stream, text);
    }
    void flush_() override {}

  private:
    Console& console_;
    std::FILE *info_, *warnings_;
};

}  // namespace

Console::Console(ConsoleOptions options) : o_(options) {
    ticker_ = std::thread([this] {
        std::unique_lock lock(mutex_);
        while (!stop_) {
            wake_.wait_for(lock, std::chrono::milliseconds(100));
            if (!stop_) tick();
        }
    });
}

Console::~Console() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    ticker_.join();
    if (barDrawn_) {
        std::fputc('\n', o_.progress);
        std::fflush(o_.progress);
    }
}

Console::Task* Console::find(long id) {
    for (Task& t : tasks_)
        if (t.id == id) return &t;
    return nullptr;
}

void Console::started(long id, const std::string& label, double total) {
    std::lock_guard lock(mutex_);
    Task t;
    t.id = id;
    t.label = label;
    t.total = total;
    tasks_.push_back(std::move(t));
}

void Console::advanced(long id, double done, double total) {
    std::lock_guard lock(mutex_);
    if (Task* t = find(id)) {
        t->done = done;
        t->total = total;
    }
}

void Console::detailed(long id, const std::string& detail) {
    std::lock_guard lock(mutex_);
    if (Task* t = find(id)) t->detail = detail;
}

void Console::finished(long id, bool completed) {
    std::lock_guard lock(mutex_);
    auto it = std::find_if(tasks_.begin(), tasks_.end(), [&](const Task& t) { return t.id == id; });
    if (it == tasks_.end()) return;
    if (it->shown) {
        const double s = it->clock.seconds();
        std::string end;
        if (completed) {
            end = "done in " + formatDuration(s);
        } else {
            end = "stopped";
            if (it->total > 0)
                end += " at " +
                       std::to_string(static_cast<int>(
                           std::floor(100.0 * std::clamp(it->done / it->total, 0.0, 1.0)))) +
                       "%";
            end += " after " + formatDuration(s);
        }
        if (!it->detail.empty()) end += " (" + it->detail + ")";
        clearBar();
        std::fprintf(o_.progress, "%s: %s\n", it->label.c_str(), end.c_str());
        std::fflush(o_.progress);
    }
    tasks_.erase(it);
}

void Console::line(std::FILE* stream, const std::string& text) {
    std::lock_guard lock(mutex_);
    clearBar();
    std::fputs(text.c_str(), stream);
    std::fputc('\n', stream);
    std::fflush(stream);
    tick();
}

int Console::columns() const {
    if (o_.width > 0) return o_.width;
    winsize ws{};
    if (::ioctl(fileno(o_.progress), TIOCGWINSZ, &ws) == 0 && ws.ws_col >= 20) return ws.ws_col;
    return 80;
}

void Console::clearBar() {
    if (!barDrawn_) return;
    std::fputs("\r\033[K", o_.progress);
    std::fflush(o_.progress);
    barDrawn_ = false;
}

void Console::draw(Task& t) {
    const double s = t.clock.seconds();
    std::string text = t.label;
    if (t.total > 0) {
        constexpr int kBar = 20;
        const int filled =
            static_cast<int>(std::floor(kBar * std::clamp(t.done / t.total, 0.0, 1.0)));
        text += " [" + std::string(static_cast<size_t>(filled), '#') +
                std::string(static_cast<size_t>(kBar - filled), '.') + "] ";
    } else {
        text += " ... ";
    }
    text += formatProgress(t.done, t.total, t.detail, s);
    const size_t room = static_cast<size_t>(columns() - 1);
    if (text.size() > room) text.resize(room);
    std::fprintf(o_.progress, "\r%s\033[K", text.c_str());
    std::fflush(o_.progress);
    barDrawn_ = true;
}

void Console::tick() {
    if (tasks_.empty()) return;
    Task& t = tasks_.back();
    const double s = t.clock.seconds();
    if (o_.terminal) {
        if (s < o_.showAfter) return;
        draw(t);
        t.shown = true;
    } else if (s >= o_.plainEvery && s - t.lastPrinted >= o_.plainEvery) {
        std::fprintf(o_.progress, "%s: %s\n", t.label.c_str(),
                     formatProgress(t.done, t.total, t.detail, s).c_str());
        std::fflush(o_.progress);
        t.lastPrinted = s;
        t.shown = true;
    }
}

std::shared_ptr<spdlog::sinks::sink> Console::logSink() {
    return std::make_shared<ConsoleLogSink>(*this, o_.info, o_.warnings);
}

}  // namespace sl
