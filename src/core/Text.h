// Small text helpers shared by the writers of files, tables and messages.
#pragma once

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace sl {

/// The whole of `text` as a finite number (std::stod's syntax), or nothing: empty text, trailing
/// characters, NaN, infinities and values out of double's range are not numbers here.
inline std::optional<double> parseFiniteNumber(const std::string& text) {
    size_t used = 0;
    double v = 0;
    try {
        v = std::stod(text, &used);
    } catch (const std::logic_error&) {
        return std::nullopt;
    }
    if (used == 0 || used != text.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

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

/// Levenshtein distance (insertions, deletions, substitutions), for "did you mean".
inline size_t editDistance(std::string_view a, std::string_view b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t up = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1] ? 1 : 0)});
            diag = up;
        }
    }
    return row[b.size()];
}

/// The candidate nearest to `word` when it is near enough to be a typo (distance at most
/// max(2, |word| / 3)), else "".
inline std::string nearestName(std::string_view word, const std::vector<std::string>& candidates) {
    std::string nearest;
    size_t best = std::string::npos;
    for (const std::string& c : candidates) {
        const size_t d = editDistance(word, c);
        if (d < best) {
            best = d;
            nearest = c;
        }
    }
    return best <= std::max<size_t>(2, word.size() / 3) ? nearest : std::string();
}

}  // namespace sl
