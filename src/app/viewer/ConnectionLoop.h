// The viewer's connections: one thread polls every open socket and reads what each sends; a
// connection goes to one of a few workers only once a whole request is buffered
// (app/viewer/RequestFrame.h), and comes back to the poll after its answer. So idle keep-alive
// connections, clients that send a byte at a time and clients that never read their answers wait
// in the poll, holding no worker; requests pipelined on one connection are answered in order, one
// at a time. Bounds: at most maxConnections open (a new one closes the least recently active
// waiting one), a connection idle for idleTimeout is closed, a request not whole within
// requestTimeout of its first byte is answered 408 and closed, an answer not written within
// writeTimeout closes its connection. Closing is graceful: the write side is shut down and what
// the client still sends is read and dropped for a moment, so that answers already sent are not
// lost to a reset.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string_view>
#include <thread>
#include <unordered_map>
#include <vector>

#include "app/viewer/RequestFrame.h"

namespace sl {

struct ConnectionLoopOptions {
    size_t workers = 8;
    size_t maxConnections = 256;
    RequestFrameLimits limits;
    std::chrono::milliseconds idleTimeout{5000};
    std::chrono::milliseconds requestTimeout{10000};
    std::chrono::milliseconds writeTimeout{2000};
    std::chrono::milliseconds lingerTimeout{1000};
};

/// What serving one request did: the bytes of the request it read, and whether the connection may
/// carry another (false: the client asked to close, or the answer could not be written).
struct ServedRequest {
    size_t consumed = 0;
    bool keepOpen = false;
};

/// Serves the whole request `request` (the front of what the connection sent) and writes its
/// answer to socket fd. Runs on a worker thread.
using ServeRequest = std::function<ServedRequest(int fd, std::string_view request)>;

/// Writes all n bytes to the non-blocking socket fd, waiting at most `timeout` for room each time
/// the socket is full. False when the peer is gone or the time ran out.
bool sendWithin(int fd, const char* data, size_t n, std::chrono::milliseconds timeout);

class ConnectionLoop {
  public:
    ConnectionLoop(ConnectionLoopOptions options, ServeRequest serve);
    ~ConnectionLoop();  // stop()
    ConnectionLoop(const ConnectionLoop&) = delete;
    ConnectionLoop& operator=(const ConnectionLoop&) = delete;

    /// Takes an accepted socket (from any thread); the loop owns and closes it.
    void adopt(int fd);
    /// Finishes the requests being served, closes every connection and joins the threads.
    void stop();

  private:
    using Clock = std::chrono::steady_clock;
    struct Connection;

    void pollLoop();
    void work();
    void wake();
    void takeHandedBack(Clock::time_point now);
    void admit(int fd, Clock::time_point now);
    void readFrom(Connection& c, Clock::time_point now);
    void examine(Connection& c, Clock::time_point now);
    void refuse(Connection& c, int status, const std::string& reason, Clock::time_point now);
    void linger(Connection& c, Clock::time_point now);
    void expire(Clock::time_point now);
    void close(int fd);

    ConnectionLoopOptions options_;
    ServeRequest serve_;
    int wakeFd_ = -1;
    // The poll thread's own: every open connection (a busy one is a worker's until handed back).
    std::unordered_map<int, std::unique_ptr<Connection>> connections_;
    // Shared, under mutex_.
    std::mutex mutex_;
    std::condition_variable ready_;
    std::deque<Connection*> whole_;  // a whole request buffered, waiting for a worker
    std::vector<Connection*> handedBack_;
    std::vector<int> accepted_;
    bool stopping_ = false;
    std::thread poller_;
    std::vector<std::thread> workers_;
};

}  // namespace sl
