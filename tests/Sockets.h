// Raw TCP clients for the viewer's server tests: connect, send, and read HTTP answers back.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <string>
#include <vector>

namespace sl::test {

/// A raw TCP connection to 127.0.0.1:port (−1 on failure).
inline int connectTo(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<uint16_t>(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(fd);
        return -1;
    }
    return fd;
}

inline void sendAll(int fd, const std::string& s) {
    size_t sent = 0;
    while (sent < s.size()) {
        const ssize_t n = ::send(fd, s.data() + sent, s.size() - sent, MSG_NOSIGNAL);
        if (n <= 0) return;
        sent += static_cast<size_t>(n);
    }
}

/// What a client read back: the final answers' statuses and bodies in order (1xx interim
/// answers skipped), and how the stream ended.
struct Answers {
    std::vector<int> statuses;
    std::vector<std::string> bodies;
    bool closed = false;  // the server closed: a clean end of stream
    bool reset = false;   // the connection was reset
};

/// Reads answers from fd until `count` final answers arrived, the stream ended, or `timeout`.
inline Answers readAnswers(int fd, size_t count, std::chrono::milliseconds timeout) {
    Answers out;
    std::string buf;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    auto parse = [&] {
        for (;;) {
            const size_t head = buf.find("\r\n\r\n");
            if (head == std::string::npos || buf.size() < 12) return;
            const int status = std::atoi(buf.c_str() + 9);
            size_t length = 0;
            std::string lower = buf.substr(0, head);
            for (char& c : lower)
                c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
            const size_t cl = lower.find("\r\ncontent-length:");
            if (cl != std::string::npos)
                length = std::strtoul(lower.c_str() + cl + 17, nullptr, 10);
            if (buf.size() < head + 4 + length) return;
            if (status >= 200) {
                out.statuses.push_back(status);
                out.bodies.push_back(buf.substr(head + 4, length));
            }
            buf.erase(0, head + 4 + length);
        }
    };
    while (out.statuses.size() < count) {
        const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
            deadline - std::chrono::steady_clock::now());
        if (left.count() <= 0) break;
        pollfd p{fd, POLLIN, 0};
        if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
        char chunk[16384];
        const ssize_t n = ::recv(fd, chunk, sizeof chunk, 0);
        if (n > 0) {
            buf.append(chunk, static_cast<size_t>(n));
            parse();
        } else if (n == 0) {
            out.closed = true;
            break;
        } else if (errno != EINTR && errno != EAGAIN) {
            out.reset = true;
            break;
        }
    }
    return out;
}

}  // namespace sl::test
