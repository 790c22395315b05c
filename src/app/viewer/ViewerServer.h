// The viewer's HTTP server (cpp-httplib, plain HTTP): every request goes to
// handleViewerRequest (app/viewer/Viewer.h); this file only moves bytes. Bound to 127.0.0.1 unless a
// host is given (the command line then warns). Request bodies over kViewerMaxBody are refused
// before they are read in full; a malformed request or a connection closed mid-transfer ends
// that connection only. The port is bound exclusively (no SO_REUSEPORT: a second viewer on the
// same port is refused); 32 connections are served at once, each closed after 1 s idle or 2 s
// without a byte, so idle or slow clients delay the others by seconds at most.
#pragma once

#include <memory>
#include <string>
#include <thread>

namespace httplib {
class Server;
}

namespace sl {

class ViewerSession;

class ViewerServer {
  public:
    /// Binds host:port (port 0: an ephemeral port, see port()). Throws InputError naming
    /// option 'port' when it cannot bind.
    ViewerServer(ViewerSession& session, const std::string& host, int port);
    ~ViewerServer();  // stops the server and joins its thread
    ViewerServer(const ViewerServer&) = delete;
    ViewerServer& operator=(const ViewerServer&) = delete;

    int port() const { return port_; }
    const std::string& host() const { return host_; }
    /// "http://127.0.0.1:8080/"
    std::string url() const;

    /// Serves on this thread until stop() (or an interrupt, see core/Interrupt.h).
    void run();
    /// Serves on a thread of its own (tests, bench view); returns once requests are accepted.
    void start();
    void stop();

  private:
    ViewerSession& session_;
    std::string host_;
    int port_ = 0;
    std::unique_ptr<httplib::Server> server_;
    std::thread thread_;
};

}  // namespace sl
