#include "app/viewer/RequestFrame.h"

#include <cctype>
#include <optional>

namespace sl {

namespace {

bool equalsNoCase(std::string_view a, std::string_view b) {
    if (a.size() != b.size()) return false;
    for (size_t i = 0; i < a.size(); ++i)
        if (std::tolower(static_cast<unsigned char>(a[i])) !=
            std::tolower(static_cast<unsigned char>(b[i])))
            return false;
    return true;
}

std::string_view trim(std::string_view s) {
    while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
    return s;
}

RequestFrame refused(int status, std::string reason) {
    RequestFrame f;
    f.state = RequestFrame::State::Refused;
    f.status = status;
    f.reason = std::move(reason);
    return f;
}

/// Digits only, no overflow past `limit + 1` (anything larger is simply "over the limit").
std::optional<size_t> parseLength(std::string_view v, size_t limit) {
    if (v.empty()) return std::nullopt;
    size_t n = 0;
    for (const char c : v) {
        if (c < '0' || c > '9') return std::nullopt;
        if (n <= limit) n = n * 10 + static_cast<size_t>(c - '0');
    }
    return n;
}

}  // namespace

RequestFrame frameRequest(std::string_view bytes, const RequestFrameLimits& limits) {
    const size_t requestLineEnd = bytes.find('\n');
    if (requestLineEnd == std::string_view::npos)
        return bytes.size() > limits.maxHeadBytes
                   ? refused(431, "request line longer than " +
                                      std::to_string(limits.maxHeadBytes) + " bytes")
                   : RequestFrame{};
    std::optional<size_t> contentLength;
    bool transferEncoded = false, expectsContinue = false;
    size_t start = requestLineEnd + 1;
    for (;;) {
        const size_t nl = bytes.find('\n', start);
        if (nl == std::string_view::npos || nl + 1 > limits.maxHeadBytes) {
            if (bytes.size() > limits.maxHeadBytes)
                return refused(431, "request head longer than " +
                                        std::to_string(limits.maxHeadBytes) + " bytes");
            return RequestFrame{};
        }
        const std::string_view line = bytes.substr(start, nl - start);  // without '\n'
        start = nl + 1;
        if (line.empty() || line.back() != '\r') continue;  // httplib skips such lines too
        const std::string_view content = line.substr(0, line.size() - 1);
        if (content.empty()) break;  // the empty line: the head ends here
        const size_t colon = content.find(':');
        if (colon == std::string_view::npos) continue;
        const std::string_view name = content.substr(0, colon);
        const std::string_view value = trim(content.substr(colon + 1));
        if (equalsNoCase(name, "content-length")) {
            const auto n = parseLength(value, limits.maxBodyBytes);
            if (!n || (contentLength && *contentLength != *n))
                return refused(400, "Content-Length '" + std::string(value.substr(0, 32)) +
                                        "' is not one whole number");
            contentLength = n;
        } else if (equalsNoCase(name, "transfer-encoding")) {
            transferEncoded = true;
        } else if (equalsNoCase(name, "expect")) {
            expectsContinue = equalsNoCase(value, "100-continue");
        }
    }
    if (transferEncoded)
        return refused(411,
                       "send the body with a Content-Length (transfer encodings such as "
                       "chunked are not taken)");
    const size_t body = contentLength.value_or(0);
    if (body > limits.maxBodyBytes)
        return refused(
            413, "request body larger than " + std::to_string(limits.maxBodyBytes) + " bytes");
    RequestFrame f;
    if (bytes.size() - start >= body) {
        f.state = RequestFrame::State::Complete;
        f.length = start + body;
    } else {
        f.expectsContinue = expectsContinue;
    }
    return f;
}

}  // namespace sl
