// Where one HTTP/1.1 request ends in the bytes a connection has sent so far: the viewer's
// connection loop (app/viewer/ConnectionLoop.h) reads every socket itself and hands a connection
// to a worker only once a whole request (head and Content-Length body) is buffered, so an idle or
// slow client never holds a worker. Lines are read as cpp-httplib reads them: the head ends at the
// first empty CRLF line after the request line; a header line not ending in CRLF is skipped.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

namespace sl {

struct RequestFrameLimits {
    size_t maxHeadBytes = 64 * 1024;    // request line and headers
    size_t maxBodyBytes = 1024 * 1024;  // Content-Length
};

struct RequestFrame {
    enum class State {
        Incomplete,  // more bytes are needed
        Complete,    // the first `length` bytes are one whole request
        Refused,     // answer `status` and close: the request cannot be taken
    };
    State state = State::Incomplete;
    size_t length = 0;
    int status = 0;
    std::string reason;
    /// Incomplete, its head whole, and it waits for "100 Continue" before sending its body.
    bool expectsContinue = false;
};

/// The first request in `bytes`. Refused: a head over the limit (431), a Content-Length that is
/// not a number or given twice differently (400) or over the body limit (413), a chunked or
/// otherwise transfer-encoded body (411: the viewer takes bodies with a Content-Length only).
RequestFrame frameRequest(std::string_view bytes, const RequestFrameLimits& limits);

}  // namespace sl
