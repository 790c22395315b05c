// Small text helpers shared by the writers of files, tables and messages.
#pragma once

#include <cctype>
#include <cstdio>
#include <string>
#include <string_view>

namespace sl {

/// printf's "%.<precision>g": the shortest of fixed and scientific notation, e.g. 0.05, 1e-06.
inline std::string formatNumber(double v, int precision = 6) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.*g", precision, v);
    return buf;
}

/// ASCII lower case (file extensions, format and colour-space names).
inline std::string lower(std::string s) {
    for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return s;
}

/// Escapes & < > " ' for XML and HTML text and attribute values.
inline std::string escapeXml(std::string_view s) {
    std::string o;
    o.reserve(s.size());
    for (char c : s) {
        switch (c) {
            case '&':
                o += "&amp;";
                break;
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '"':
                o += "&quot;";
                break;
            case '\'':
                o += "&#39;";
                break;
            default:
                o += c;
        }
    }
    return o;
}

}  // namespace sl
