#include "app/viewer/ViewerServer.h"

#include <httplib.h>

#include <atomic>
#include <chrono>

#include "app/viewer/Viewer.h"
#include "core/Error.h"
#include "core/Interrupt.h"

namespace sl {

namespace {

constexpr size_t kViewerThreads = 32;  // connections served at once

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

}  // namespace

ViewerServer::ViewerServer(ViewerSession& session, const std::string& host, int port)
    : session_(session), host_(host), server_(std::make_unique<httplib::Server>()) {
    httplib::Server& s = *server_;
    s.set_payload_max_length(kViewerMaxBody);
    // Idle or slow clients may not starve the others: a pool of kViewerThreads connections, each
    // closed after 1 s idle between requests or 2 s without a byte of a request.
    s.new_task_queue = [] { return new httplib::ThreadPool(kViewerThreads); };
    s.set_read_timeout(2, 0);
    s.set_write_timeout(5, 0);
    s.set_keep_alive_timeout(1);
    s.set_keep_alive_max_count(1000);
    s.set_tcp_nodelay(true);
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
        if (!s.bind_to_port(host, port))
            throw inputError(
                option("port"),
                "port " + std::to_string(port) + " is taken (or not allowed) on " + host,
                "stop the program that uses it, or give another (0: any free port)");
        port_ = port;
    }
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
}

}  // namespace sl
