// The viewer's HTTP server (cpp-httplib, plain HTTP): every request goes to
// handleViewerRequest (app/viewer/ViewerApi.h); this file only moves bytes. Bound to 127.0.0.1
// unless a host is given (the command line then warns). The port is bound exclusively (no
// SO_REUSEPORT: a second viewer on the same port is refused). httplib accepts and parses; the
// connections themselves are ours (app/viewer/ConnectionLoop.h): one thread reads every socket and
// a worker gets a connection only with a whole request buffered, so idle, slow or non-reading
// clients hold no worker, and pipelined requests are answered in order. Request bodies over
// kViewerMaxBody are refused before they are read; a malformed request or a connection closed
// mid-transfer ends that connection only.
#pragma once

#include <memory>
#include <string>
#include <thread>

namespace sl {

class ViewerSession;
class ConnectionLoop;
class ViewerHttp;

/// Throws InputError naming option 'port' when host:port cannot be bound now (another program
/// holds it, or the address is not this machine's). `view` asks before it traces T and the judge,
/// so a taken port is said at once, not minutes later; ViewerServer binds again (and says the
/// same should the port be taken in between). Port 0 (any free port) always passes.
void checkViewerPort(const std::string& host, int port);

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
    std::unique_ptr<ViewerHttp> server_;
    std::unique_ptr<ConnectionLoop> connections_;
    std::thread thread_;
};

}  // namespace sl
