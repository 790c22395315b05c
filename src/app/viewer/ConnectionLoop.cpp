#include "app/viewer/ConnectionLoop.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace sl {

struct ConnectionLoop::Connection {
    int fd = -1;
    std::string in;                  // read and not yet served
    size_t request = 0;              // busy: the length of the whole request at the front of `in`
    Clock::time_point lastActive;    // a byte read or an answer sent
    Clock::time_point requestStart;  // the first byte of the request being received
    Clock::time_point lingerUntil;
    bool peerClosed = false;    // the client shut its side
    bool continueSent = false;  // "100 Continue" sent for the request being received
    bool busy = false;          // a worker's until handed back
    bool closeAfter = false;    // set by the worker: close once handed back
    bool lingering = false;     // our side shut; dropping what still arrives
};

namespace {

using namespace std::chrono_literals;

const char* statusText(int status) {
    switch (status) {
        case 400:
            return "Bad Request";
        case 408:
            return "Request Timeout";
        case 411:
            return "Length Required";
        case 413:
            return "Payload Too Large";
        case 431:
            return "Request Header Fields Too Large";
        default:
            return "Error";
    }
}

/// Printable ASCII without quotes or backslashes: safe inside a JSON string as it is.
std::string printable(const std::string& s) {
    std::string out = s;
    for (char& c : out)
        if (c < 0x20 || c > 0x7e || c == '"' || c == '\\') c = '?';
    return out;
}

}  // namespace

bool sendWithin(int fd, const char* data, size_t n, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    size_t sent = 0;
    while (sent < n) {
        const ssize_t k = ::send(fd, data + sent, n - sent, MSG_NOSIGNAL | MSG_DONTWAIT);
        if (k > 0) {
            sent += static_cast<size_t>(k);
            continue;
        }
        if (k < 0 && errno == EINTR) continue;
        if (k < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
            const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
                deadline - std::chrono::steady_clock::now());
            if (left.count() <= 0) return false;
            pollfd p{fd, POLLOUT, 0};
            const int r = ::poll(&p, 1, static_cast<int>(left.count()));
            if (r < 0 && errno == EINTR) continue;
            if (r <= 0 || (p.revents & (POLLERR | POLLHUP | POLLNVAL))) return false;
            continue;
        }
        return false;
    }
    return true;
}

ConnectionLoop::ConnectionLoop(ConnectionLoopOptions options, ServeRequest serve)
    : options_(options), serve_(std::move(serve)) {
    wakeFd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (wakeFd_ < 0) throw std::runtime_error("the viewer cannot create its wake-up event");
    poller_ = std::thread([this] { pollLoop(); });
    for (size_t k = 0; k < std::max<size_t>(1, options_.workers); ++k)
        workers_.emplace_back([this] { work(); });
}

ConnectionLoop::~ConnectionLoop() {
    stop();
}

void ConnectionLoop::adopt(int fd) {
    {
        std::lock_guard lock(mutex_);
        if (!stopping_) {
            accepted_.push_back(fd);
            fd = -1;
        }
    }
    if (fd >= 0)
        ::close(fd);
    else
        wake();
}

void ConnectionLoop::stop() {
    {
        std::lock_guard lock(mutex_);
        stopping_ = true;
    }
    ready_.notify_all();
    if (wakeFd_ >= 0) wake();
    if (poller_.joinable()) poller_.join();
    for (auto& w : workers_)
        if (w.joinable()) w.join();
    workers_.clear();
    for (const auto& entry : connections_) ::close(entry.first);
    connections_.clear();
    for (const int fd : accepted_) ::close(fd);
    accepted_.clear();
    if (wakeFd_ >= 0) ::close(wakeFd_);
    wakeFd_ = -1;
}

void ConnectionLoop::wake() {
    const uint64_t one = 1;
    [[maybe_unused]] const ssize_t n = ::write(wakeFd_, &one, sizeof one);
}

void ConnectionLoop::work() {
    for (;;) {
        Connection* c = nullptr;
        {
            std::unique_lock lock(mutex_);
            ready_.wait(lock, [this] { return stopping_ || !whole_.empty(); });
            if (stopping_) return;
            c = whole_.front();
            whole_.pop_front();
        }
        ServedRequest served;
        try {
            served = serve_(c->fd, std::string_view(c->in).substr(0, c->request));
        } catch (...) {
            served = ServedRequest{};
        }
        // A request the server read differently from its frame (a malformed one) ends the
        // connection: what follows it cannot be trusted to start a request.
        c->closeAfter = !served.keepOpen || served.consumed != c->request;
        c->in.erase(0, c->request);
        {
            std::lock_guard lock(mutex_);
            handedBack_.push_back(c);
        }
        wake();
    }
}

void ConnectionLoop::pollLoop() {
    std::vector<pollfd> fds;
    std::vector<Connection*> polled;
    for (;;) {
        {
            std::lock_guard lock(mutex_);
            if (stopping_) return;
        }
        const auto before = Clock::now();
        auto next = before + 1s;
        fds.assign(1, pollfd{wakeFd_, POLLIN, 0});
        polled.clear();
        for (const auto& [fd, c] : connections_) {
            if (c->busy) continue;
            fds.push_back(pollfd{fd, POLLIN, 0});
            polled.push_back(c.get());
            const auto due = c->lingering    ? c->lingerUntil
                             : c->in.empty() ? c->lastActive + options_.idleTimeout
                                             : c->requestStart + options_.requestTimeout;
            next = std::min(next, due);
        }
        const auto waitMs = std::clamp<int64_t>(
            std::chrono::duration_cast<std::chrono::milliseconds>(next - before).count() + 1, 0,
            1000);
        const int n = ::poll(fds.data(), fds.size(), static_cast<int>(waitMs));
        if (n < 0 && errno != EINTR) std::this_thread::sleep_for(10ms);
        const auto now = Clock::now();
        if (n > 0 && (fds[0].revents & POLLIN)) {
            uint64_t count = 0;
            [[maybe_unused]] const ssize_t r = ::read(wakeFd_, &count, sizeof count);
        }
        // The polled connections first: admitting new ones may close (and free) one of them.
        for (size_t i = 0; n > 0 && i < polled.size(); ++i)
            if (fds[i + 1].revents & (POLLIN | POLLHUP | POLLERR)) readFrom(*polled[i], now);
        takeHandedBack(now);
        std::vector<int> accepted;
        {
            std::lock_guard lock(mutex_);
            accepted.swap(accepted_);
        }
        for (const int fd : accepted) admit(fd, now);
        expire(now);
    }
}

void ConnectionLoop::takeHandedBack(Clock::time_point now) {
    std::vector<Connection*> back;
    {
        std::lock_guard lock(mutex_);
        back.swap(handedBack_);
    }
    for (Connection* c : back) {
        c->busy = false;
        c->continueSent = false;
        c->lastActive = now;
        c->requestStart = now;
        if (c->closeAfter)
            linger(*c, now);
        else
            examine(*c, now);  // the next pipelined request may be whole already
    }
}

void ConnectionLoop::admit(int fd, Clock::time_point now) {
    const int flags = ::fcntl(fd, F_GETFL, 0);
    const int one = 1;
    if (flags < 0 || ::fcntl(fd, F_SETFL, flags | O_NONBLOCK) < 0) {
        ::close(fd);
        return;
    }
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (connections_.size() >= options_.maxConnections) {
        // Room for the newcomer: close a lingering connection, else the one idle longest.
        Connection* victim = nullptr;
        for (const auto& entry : connections_) {
            Connection* c = entry.second.get();
            if (c->busy) continue;
            if (!victim || (c->lingering && !victim->lingering) ||
                (c->lingering == victim->lingering && c->lastActive < victim->lastActive))
                victim = c;
        }
        if (!victim) {
            ::close(fd);
            return;
        }
        close(victim->fd);
    }
    auto c = std::make_unique<Connection>();
    c->fd = fd;
    c->lastActive = now;
    c->requestStart = now;
    connections_[fd] = std::move(c);
}

void ConnectionLoop::readFrom(Connection& c, Clock::time_point now) {
    constexpr size_t kChunk = 16 * 1024, kPerTurn = 64 * 1024;
    char buf[kChunk];
    size_t got = 0;
    bool failed = false;
    while (got < kPerTurn) {
        const ssize_t k = ::recv(c.fd, buf, sizeof buf, 0);
        if (k > 0) {
            if (!c.lingering) {
                if (c.in.empty()) c.requestStart = now;
                c.in.append(buf, static_cast<size_t>(k));
                c.lastActive = now;
            }
            got += static_cast<size_t>(k);
        } else if (k == 0) {
            c.peerClosed = true;
            break;
        } else if (errno == EINTR) {
            continue;
        } else {
            failed = errno != EAGAIN && errno != EWOULDBLOCK;
            break;
        }
    }
    if (failed || (c.lingering && c.peerClosed)) {
        close(c.fd);
        return;
    }
    if (!c.lingering) examine(c, now);
}

void ConnectionLoop::examine(Connection& c, Clock::time_point now) {
    if (c.in.empty()) {
        if (c.peerClosed) close(c.fd);
        return;
    }
    const RequestFrame f = frameRequest(c.in, options_.limits);
    switch (f.state) {
        case RequestFrame::State::Complete: {
            c.request = f.length;
            c.busy = true;
            {
                std::lock_guard lock(mutex_);
                whole_.push_back(&c);
            }
            ready_.notify_one();
            return;
        }
        case RequestFrame::State::Refused:
            refuse(c, f.status, f.reason, now);
            return;
        case RequestFrame::State::Incomplete:
            if (c.peerClosed) {
                close(c.fd);  // half a request and no more to come: nothing to answer
            } else if (f.expectsContinue && !c.continueSent) {
                static constexpr char kContinue[] = "HTTP/1.1 100 Continue\r\n\r\n";
                sendWithin(c.fd, kContinue, sizeof kContinue - 1, 0ms);
                c.continueSent = true;
            }
            return;
    }
}

void ConnectionLoop::refuse(Connection& c, int status, const std::string& reason,
                            Clock::time_point now) {
    const std::string body = "{\"error\": \"" + printable(reason) + "\"}";
    const std::string answer =
        "HTTP/1.1 " + std::to_string(status) + " " + statusText(status) +
        "\r\nContent-Type: application/json\r\nContent-Length: " + std::to_string(body.size()) +
        "\r\nConnection: close\r\n\r\n" + body;
    sendWithin(c.fd, answer.data(), answer.size(), 0ms);  // best effort: never block the poll
    linger(c, now);
}

void ConnectionLoop::linger(Connection& c, Clock::time_point now) {
    if (c.peerClosed) {
        close(c.fd);
        return;
    }
    ::shutdown(c.fd, SHUT_WR);
    c.in.clear();
    c.lingering = true;
    c.lingerUntil = now + options_.lingerTimeout;
}

void ConnectionLoop::expire(Clock::time_point now) {
    std::vector<Connection*> due;
    for (const auto& entry : connections_) {
        Connection* c = entry.second.get();
        if (c->busy) continue;
        if ((c->lingering && now >= c->lingerUntil) ||
            (!c->lingering && c->in.empty() && now >= c->lastActive + options_.idleTimeout) ||
            (!c->lingering && !c->in.empty() && now >= c->requestStart + options_.requestTimeout))
            due.push_back(c);
    }
    for (Connection* c : due) {
        if (c->lingering || c->in.empty())
            close(c->fd);
        else
            refuse(*c, 408, "the request did not arrive in time", now);
    }
}

void ConnectionLoop::close(int fd) {
    ::close(fd);
    connections_.erase(fd);
}

}  // namespace sl
