#include "app/viewer/ViewerServer.h"

#include <arpa/inet.h>
#include <httplib.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <string_view>

#include "app/viewer/ConnectionLoop.h"
#include "app/viewer/ViewerApi.h"
#include "core/Error.h"
#include "core/Interrupt.h"

namespace sl {

namespace {

constexpr size_t kViewerWorkers = 8;  // requests served at once (whole ones only)
constexpr std::chrono::milliseconds kWriteTimeout{2000};
constexpr time_t kIdleSeconds = 5;

void answer(ViewerSession& session, const httplib::Request& req, httplib::Response& res) {
    ViewerRequest r;
    r.method = req.method;
    r.path = req.path;
    for (const auto& [k, v] : req.params) r.query[k] = v;
    r.body = req.body;
    const ViewerResponse out = handleViewerRequest(session, r);
    res.status = out.status;
    res.set_header("Cache-Control", "no-store");
    res.set_content(out.body, out.contentType.c_str());
}

void socketAddress(int fd, bool local, std::string& ip, int& port) {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    auto* sa = reinterpret_cast<sockaddr*>(&a);
    if ((local ? ::getsockname(fd, sa, &len) : ::getpeername(fd, sa, &len)) != 0) return;
    char text[INET6_ADDRSTRLEN] = {};
    if (a.ss_family == AF_INET) {
        const auto* in = reinterpret_cast<const sockaddr_in*>(&a);
        ::inet_ntop(AF_INET, &in->sin_addr, text, sizeof text);
        port = ntohs(in->sin_port);
    } else if (a.ss_family == AF_INET6) {
        const auto* in = reinterpret_cast<const sockaddr_in6*>(&a);
        ::inet_ntop(AF_INET6, &in->sin6_addr, text, sizeof text);
        port = ntohs(in->sin6_port);
    }
    ip = text;
}

/// One whole request, as the connection loop buffered it, read as httplib's stream; the answer
/// goes to the socket within kWriteTimeout.
class RequestStream final : public httplib::Stream {
  public:
    RequestStream(int fd, std::string_view request) : fd_(fd), request_(request) {}

    bool is_readable() const override { return read_ < request_.size(); }
    bool is_writable() const override { return writable_; }
    ssize_t read(char* ptr, size_t size) override {
        const size_t n = std::min(size, request_.size() - read_);
        std::memcpy(ptr, request_.data() + read_, n);
        read_ += n;
        return static_cast<ssize_t>(n);
    }
    ssize_t write(const char* ptr, size_t size) override {
        writable_ = writable_ && sendWithin(fd_, ptr, size, kWriteTimeout);
        return writable_ ? static_cast<ssize_t>(size) : -1;
    }
    void get_remote_ip_and_port(std::string& ip, int& port) const override {
        socketAddress(fd_, false, ip, port);
    }
    void get_local_ip_and_port(std::string& ip, int& port) const override {
        socketAddress(fd_, true, ip, port);
    }
    socket_t socket() const override { return fd_; }

    size_t consumed() const { return read_; }

  private:
    int fd_;
    std::string_view request_;
    size_t read_ = 0;
    bool writable_ = true;
};

/// httplib's acceptor hands each socket to its task queue; ours hands it on to the connection
/// loop at once (ViewerHttp::process_and_close_socket), so the acceptor never waits for a worker.
class HandOn final : public httplib::TaskQueue {
  public:
    void enqueue(std::function<void()> fn) override { fn(); }
    void shutdown() override {}
};

}  // namespace

/// httplib's server with the connections taken over: accepted sockets go to the ConnectionLoop,
/// which calls serve() with each whole request.
class ViewerHttp final : public httplib::Server {
  public:
    void handTo(ConnectionLoop* loop) { loop_ = loop; }
    /// httplib listens with a backlog of 5: a burst of connections beyond it waits for the
    /// client's SYN to be resent (1 s, 3 s, ...) before the acceptor sees it. Listening again
    /// sets the backlog (Linux).
    void widenBacklog() { ::listen(svr_sock_.load(), SOMAXCONN); }
    /// httplib's stop() closes the listening socket only while it serves: a server bound and
    /// never run (a setup that failed after the bind, a test) kept its port until the process
    /// ended.
    ~ViewerHttp() override {
        const socket_t sock = svr_sock_.exchange(INVALID_SOCKET);
        if (sock != INVALID_SOCKET) ::close(sock);
    }

    ServedRequest serve(int fd, std::string_view request) {
        RequestStream stream(fd, request);
        bool clientCloses = false;
        const bool ok = process_request(stream, false, clientCloses, nullptr);
        return {stream.consumed(), ok && !clientCloses && stream.is_writable()};
    }

  private:
    bool process_and_close_socket(socket_t sock) override {
        loop_->adopt(sock);
        return true;
    }

    ConnectionLoop* loop_ = nullptr;
};

namespace {

InputError portTaken(const std::string& host, int port) {
    return inputError(option("port"),
                      "port " + std::to_string(port) + " is taken (or not allowed) on " + host,
                      "stop the program that uses it, or give another (0: any free port)");
}

}  // namespace

void checkViewerPort(const std::string& host, int port) {
    if (port == 0) return;
    addrinfo hints{};
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    hints.ai_flags = AI_PASSIVE;
    addrinfo* found = nullptr;
    if (getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found) != 0 || !found)
        throw inputError(option("host"), "cannot listen on " + host,
                         "give a local address such as 127.0.0.1");
    bool bound = false;
    for (addrinfo* a = found; a && !bound; a = a->ai_next) {
        const int fd = socket(a->ai_family, a->ai_socktype, a->ai_protocol);
        if (fd < 0) continue;
        int yes = 1;  // as the server binds: SO_REUSEADDR, not SO_REUSEPORT
        setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));
        bound = bind(fd, a->ai_addr, a->ai_addrlen) == 0 && listen(fd, 1) == 0;
        close(fd);
    }
    freeaddrinfo(found);
    if (!bound) throw portTaken(host, port);
}

ViewerServer::ViewerServer(ViewerSession& session, const std::string& host, int port)
    : session_(session), host_(host), server_(std::make_unique<ViewerHttp>()) {
    ConnectionLoopOptions co;
    co.workers = kViewerWorkers;
    co.limits.maxBodyBytes = kViewerMaxBody;
    co.idleTimeout = std::chrono::seconds(kIdleSeconds);
    co.writeTimeout = kWriteTimeout;
    connections_ = std::make_unique<ConnectionLoop>(
        co, [this](int fd, std::string_view request) { return server_->serve(fd, request); });
    server_->handTo(connections_.get());
    ViewerHttp& s = *server_;
    s.new_task_queue = [] { return new HandOn; };
    s.set_payload_max_length(kViewerMaxBody);
    s.set_keep_alive_timeout(kIdleSeconds);  // only what the answers' Keep-Alive header says
    s.set_keep_alive_max_count(1000000);
    // The port is ours alone: SO_REUSEADDR (a restart binds at once) but not httplib's default
    // SO_REUSEPORT, with which a second viewer bound the same port and took half its requests.
    s.set_socket_options([](socket_t sock) {
        int yes = 1;
        setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, reinterpret_cast<const void*>(&yes),
                   sizeof(yes));
    });
    auto handler = [this](const httplib::Request& req, httplib::Response& res) {
        answer(session_, req, res);
    };
    s.Get(".*", handler);
    s.Post(".*", handler);
    s.set_exception_handler(
        [](const httplib::Request&, httplib::Response& res, std::exception_ptr) {
            res.status = 500;
            res.set_content("{\"error\": \"internal error\"}", "application/json");
        });
    if (port == 0) {
        port_ = s.bind_to_any_port(host);
        if (port_ <= 0)
            throw inputError(option("host"), "cannot listen on " + host,
                             "give a local address such as 127.0.0.1");
    } else {
        if (!s.bind_to_port(host, port)) throw portTaken(host, port);
        port_ = port;
    }
    s.widenBacklog();
}

ViewerServer::~ViewerServer() {
    stop();
}

std::string ViewerServer::url() const {
    std::string u = "http://";
    u += host_;
    u += ":";
    u += std::to_string(port_);
    u += "/";
    return u;
}

void ViewerServer::run() {
    std::atomic<bool> done{false};
    std::thread watch([this, &done] {
        while (!done) {
            if (interruptRequested()) {
                server_->stop();
                return;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
    });
    server_->listen_after_bind();
    done = true;
    watch.join();
}

void ViewerServer::start() {
    thread_ = std::thread([this] { server_->listen_after_bind(); });
    for (int k = 0; k < 500 && !server_->is_running(); ++k)
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

void ViewerServer::stop() {
    if (server_) server_->stop();
    if (thread_.joinable()) thread_.join();
    if (connections_) connections_->stop();
}

}  // namespace sl
