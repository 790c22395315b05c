// The viewer's connections (app/viewer/RequestFrame.h, app/viewer/ConnectionLoop.h): where a
// request ends in the bytes so far, exactly, at every split point; and the loop, with a server that
// answers each request with its path: pipelined requests answered in order, idle connections
// holding no worker, the idle, request and connection-count bounds, refusals and clean closes.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "Sockets.h"
#include "app/viewer/ConnectionLoop.h"
#include "app/viewer/RequestFrame.h"

using namespace sl;
using namespace std::chrono_literals;
using State = RequestFrame::State;

namespace {

RequestFrameLimits limits(size_t head = 1024, size_t body = 100) {
    RequestFrameLimits l;
    l.maxHeadBytes = head;
    l.maxBodyBytes = body;
    return l;
}

/// The path of a request line ("GET /a HTTP/1.1" → "/a").
std::string pathOf(std::string_view request) {
    const size_t a = request.find(' '), b = request.find(' ', a + 1);
    return std::string(request.substr(a + 1, b - a - 1));
}

/// A listening socket on 127.0.0.1 whose accepted connections go to a ConnectionLoop whose
/// server answers 200 with the request's path; "/short" is read one byte short (as a request
/// the parser reads differently).
class PathServer {
  public:
    explicit PathServer(ConnectionLoopOptions o)
        : loop_(o, [this](int fd, std::string_view request) { return serve(fd, request); }) {
        listen_ = ::socket(AF_INET, SOCK_STREAM, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        socklen_t len = sizeof a;
        if (::bind(listen_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 ||
            ::listen(listen_, 512) != 0 ||
            ::getsockname(listen_, reinterpret_cast<sockaddr*>(&a), &len) != 0)
            throw std::runtime_error("cannot listen");
        port_ = ntohs(a.sin_port);
        acceptor_ = std::thread([this] {
            for (;;) {
                const int fd = ::accept(listen_, nullptr, nullptr);
                if (fd < 0) return;
                loop_.adopt(fd);
            }
        });
    }
    ~PathServer() {
        ::shutdown(listen_, SHUT_RDWR);
        acceptor_.join();
        ::close(listen_);
        loop_.stop();
    }
    int port() const { return port_; }
    int served() const { return served_; }

  private:
    ServedRequest serve(int fd, std::string_view request) {
        const std::string path = pathOf(request);
        const std::string answer =
            "HTTP/1.1 200 OK\r\nContent-Length: " + std::to_string(path.size()) + "\r\n\r\n" + path;
        const bool ok = sendWithin(fd, answer.data(), answer.size(), 2000ms);
        ++served_;
        const bool closes = request.find("Connection: close") != std::string_view::npos;
        return {request.size() - (path == "/short" ? 1 : 0), ok && !closes};
    }

    ConnectionLoop loop_;
    int listen_ = -1;
    int port_ = 0;
    std::atomic<int> served_{0};
    std::thread acceptor_;
};

std::string get(const std::string& path, const std::string& extra = "") {
    return "GET " + path + " HTTP/1.1\r\nHost: x\r\n" + extra + "\r\n";
}

double secondsSince(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

TEST(RequestFrame, EndsWhereTheHeadAndItsContentLengthEndAtEverySplitPoint) {
    const std::string first =
        "POST /light HTTP/1.1\r\nHost: x\r\nContent-Length: 7\r\n\r\n{\"E\":1}";
    const std::string second = get("/info");
    const std::string both = first + second;
    for (size_t k = 0; k <= both.size(); ++k) {
        const RequestFrame f = frameRequest(std::string_view(both).substr(0, k), limits());
        if (k < first.size()) {
            EXPECT_EQ(f.state, State::Incomplete) << k;
        } else {
            ASSERT_EQ(f.state, State::Complete) << k;
            EXPECT_EQ(f.length, first.size()) << k;
        }
    }
    const RequestFrame g = frameRequest(std::string_view(both).substr(first.size()), limits());
    ASSERT_EQ(g.state, State::Complete);
    EXPECT_EQ(g.length, second.size());
}

TEST(RequestFrame, ReadsLinesAsHttplibDoes) {
    // Header names in any case; a line ending in a bare LF is skipped (httplib skips it too).
    const std::string lower = "POST / HTTP/1.1\r\ncontent-LENGTH:  3 \r\n\r\nabc";
    EXPECT_EQ(frameRequest(lower, limits()).length, lower.size());
    const std::string bareLf = "POST / HTTP/1.1\r\nContent-Length: 3\n\r\nabc";
    EXPECT_EQ(frameRequest(bareLf, limits()).length, bareLf.size() - 3);
    // The same length twice is one length.
    const std::string twice = "POST / HTTP/1.1\r\nContent-Length: 2\r\nContent-Length: 2\r\n\r\nab";
    EXPECT_EQ(frameRequest(twice, limits()).length, twice.size());
}

TEST(RequestFrame, RefusesWhatCannotBeTakenWithItsStatus) {
    auto status = [](const std::string& bytes, RequestFrameLimits l = limits()) {
        const RequestFrame f = frameRequest(bytes, l);
        return f.state == State::Refused ? f.status : 0;
    };
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: 101\r\n\r\n"), 413);
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: 100\r\n\r\n"), 0);  // at the limit
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: 99999999999999999999999\r\n\r\n"), 413);
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: 1e3\r\n\r\n"), 400);
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: -1\r\n\r\n"), 400);
    EXPECT_EQ(status("POST / HTTP/1.1\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n"), 400);
    EXPECT_EQ(status("POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n3\r\nabc\r\n0\r\n\r\n"),
              411);
    // A head over the limit, whole or not.
    EXPECT_EQ(status("GET /" + std::string(2000, 'a') + " HTTP/1.1\r\n\r\n"), 431);
    EXPECT_EQ(status("GET /" + std::string(2000, 'a')), 431);
    EXPECT_EQ(status("GET / HTTP/1.1\r\nX: " + std::string(2000, 'a')), 431);
    EXPECT_EQ(status("GET /" + std::string(1000, 'a')), 0);  // not yet over
}

TEST(RequestFrame, SaysWhenTheClientWaitsForContinue) {
    const std::string head = "POST / HTTP/1.1\r\nExpect: 100-continue\r\nContent-Length: 3\r\n\r\n";
    EXPECT_TRUE(frameRequest(head, limits()).expectsContinue);
    EXPECT_FALSE(frameRequest(head.substr(0, head.size() - 2), limits()).expectsContinue);
    EXPECT_EQ(frameRequest(head + "abc", limits()).state, State::Complete);
}

TEST(ConnectionLoop, AnswersPipelinedRequestsInOrderAndClosesCleanly) {
    ConnectionLoopOptions o;
    o.workers = 4;
    PathServer server(o);
    const int fd = test::connectTo(server.port());
    ASSERT_GE(fd, 0);
    std::string all;
    for (int k = 0; k < 50; ++k) all += get("/r" + std::to_string(k));
    all += get("/last", "Connection: close\r\n");
    test::sendAll(fd, all);
    const test::Answers a = test::readAnswers(fd, 52, 10s);
    ::close(fd);
    ASSERT_EQ(a.statuses.size(), 51u);
    for (int k = 0; k < 50; ++k) EXPECT_EQ(a.bodies[k], "/r" + std::to_string(k));
    EXPECT_EQ(a.bodies[50], "/last");
    EXPECT_TRUE(a.closed) << "the connection was not closed after 'Connection: close'";
    EXPECT_FALSE(a.reset);
}

TEST(ConnectionLoop, IdleAndSlowClientsHoldNoWorker) {
    ConnectionLoopOptions o;
    o.workers = 2;
    PathServer server(o);
    std::vector<int> idle;
    for (int k = 0; k < 200; ++k) idle.push_back(test::connectTo(server.port()));
    // Two clients with half a request each, waiting to send the rest.
    const std::string slow = get("/slowly");
    std::vector<int> dribble = {test::connectTo(server.port()), test::connectTo(server.port())};
    for (const int fd : dribble) test::sendAll(fd, slow.substr(0, 5));
    const auto t0 = std::chrono::steady_clock::now();
    const int fd = test::connectTo(server.port());
    test::sendAll(fd, get("/now"));
    const test::Answers a = test::readAnswers(fd, 1, 10s);
    const double seconds = secondsSince(t0);
    ::close(fd);
    ASSERT_EQ(a.statuses.size(), 1u);
    EXPECT_EQ(a.bodies[0], "/now");
    EXPECT_LT(seconds, 1.0);
    // The dribbling clients finish their requests and are answered too.
    for (const int d : dribble) {
        test::sendAll(d, slow.substr(5));
        const test::Answers b = test::readAnswers(d, 1, 10s);
        ASSERT_EQ(b.statuses.size(), 1u);
        EXPECT_EQ(b.bodies[0], "/slowly");
        ::close(d);
    }
    for (const int i : idle) ::close(i);
}

TEST(ConnectionLoop, ClosesIdleConnectionsAndAnswersLateRequests408) {
    ConnectionLoopOptions o;
    o.idleTimeout = 200ms;
    o.requestTimeout = 300ms;
    PathServer server(o);
    const int idle = test::connectTo(server.port());
    const int late = test::connectTo(server.port());
    test::sendAll(late, "GET /never HTTP/1.1\r\n");
    const auto t0 = std::chrono::steady_clock::now();
    const test::Answers i = test::readAnswers(idle, 1, 5s);
    EXPECT_TRUE(i.closed);
    EXPECT_TRUE(i.statuses.empty());
    EXPECT_LT(secondsSince(t0), 2.0);
    const test::Answers l = test::readAnswers(late, 2, 5s);
    ASSERT_EQ(l.statuses.size(), 1u);
    EXPECT_EQ(l.statuses[0], 408);
    EXPECT_TRUE(l.closed);
    ::close(idle);
    ::close(late);
    EXPECT_EQ(server.served(), 0);
}

TEST(ConnectionLoop, RefusesWithoutReadingAndMakesRoomForNewcomers) {
    ConnectionLoopOptions o;
    o.maxConnections = 4;
    o.limits = limits(1024, 100);
    PathServer server(o);
    // A body over the limit: 413 at once, the body never sent; the close is clean.
    const int big = test::connectTo(server.port());
    test::sendAll(big, "POST /big HTTP/1.1\r\nContent-Length: 1000\r\n\r\n");
    const test::Answers b = test::readAnswers(big, 2, 5s);
    ASSERT_EQ(b.statuses.size(), 1u);
    EXPECT_EQ(b.statuses[0], 413);
    EXPECT_TRUE(b.closed);
    ::close(big);
    // A request the server reads differently from its frame: answered, then the connection ends.
    const int odd = test::connectTo(server.port());
    test::sendAll(odd, get("/short") + get("/after"));
    const test::Answers s = test::readAnswers(odd, 2, 5s);
    ASSERT_EQ(s.statuses.size(), 1u);
    EXPECT_TRUE(s.closed);
    ::close(odd);
    // Four idle connections fill the loop; a fifth is served, the one idle longest closed.
    std::vector<int> idle;
    for (int k = 0; k < 4; ++k) {
        idle.push_back(test::connectTo(server.port()));
        std::this_thread::sleep_for(20ms);
    }
    const int fifth = test::connectTo(server.port());
    test::sendAll(fifth, get("/fifth"));
    const test::Answers f = test::readAnswers(fifth, 1, 5s);
    ASSERT_EQ(f.statuses.size(), 1u);
    EXPECT_EQ(f.bodies[0], "/fifth");
    EXPECT_TRUE(test::readAnswers(idle[0], 1, 2s).closed);
    ::close(fifth);
    for (const int i : idle) ::close(i);
}
