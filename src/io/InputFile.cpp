#include "io/InputFile.h"

#include <fstream>
#include <nlohmann/json.hpp>

#include "core/Error.h"

namespace sl {

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

std::string byteCount(uint64_t n) {
    if (n >= (1ull << 20)) return std::to_string(n >> 20) + " MiB";
    if (n >= (1ull << 10)) return std::to_string(n >> 10) + " KiB";
    return std::to_string(n) + " bytes";
}

std::string withFix(const std::string& fix, const std::string& fallback) {
    return fix.empty() ? fallback : fix;
}

void appendExcerpt(const json& v, std::string& out, size_t limit) {
    if (out.size() > limit) return;
    switch (v.type()) {
        case json::value_t::object: {
            out += '{';
            bool first = true;
            for (auto it = v.begin(); it != v.end(); ++it) {
                if (out.size() > limit) return;
                if (!first) out += ", ";
                first = false;
                appendExcerpt(json(it.key()), out, limit);
                out += ": ";
                appendExcerpt(it.value(), out, limit);
            }
            out += '}';
            return;
        }
        case json::value_t::array: {
            out += '[';
            bool first = true;
            for (const json& e : v) {
                if (out.size() > limit) return;
                if (!first) out += ", ";
                first = false;
                appendExcerpt(e, out, limit);
            }
            out += ']';
            return;
        }
        case json::value_t::string: {
            const std::string& s = v.get_ref<const std::string&>();
            // Quote at most what fits; dump() escapes (and replaces a UTF-8 sequence cut short).
            out += json(s.substr(0, limit + 1 - std::min(out.size(), limit + 1)))
                       .dump(-1, ' ', false, json::error_handler_t::replace);
            return;
        }
        default:
            out += v.dump(-1, ' ', false, json::error_handler_t::replace);
    }
}

}  // namespace

void checkInputFile(const fs::path& file, const std::string& what, uint64_t maxBytes,
                    const std::string& fix) {
    const std::string where = file.string();
    std::error_code ec;
    const fs::file_status st = fs::status(file, ec);  // follows symlinks; never opens the file
    if (!fs::exists(st))
        throw inputError(where, "cannot open " + what + ": no such file",
                         withFix(fix, "check the path"));
    if (fs::is_directory(st))
        throw inputError(where, "is a directory, not " + what, withFix(fix, "give a file"));
    if (!fs::is_regular_file(st))
        throw inputError(
            where,
            "is not a regular file (a FIFO, device or socket), not " + what + "; it is not read",
            withFix(fix, "give a file"));
    const uintmax_t size = fs::file_size(file, ec);
    if (ec)
        throw inputError(where, "cannot read " + what + ": " + ec.message(),
                         withFix(fix, "check the path and its permissions"));
    if (size > maxBytes)
        throw inputError(where,
                         "is " + std::to_string(size) + " bytes, more than " + what +
                             " can be (at most " + byteCount(maxBytes) + ")",
                         withFix(fix, "check the path"));
}

std::string readInputFile(const fs::path& file, const std::string& what, uint64_t maxBytes,
                          const std::string& fix) {
    checkInputFile(file, what, maxBytes, fix);
    std::ifstream in(file, std::ios::binary);
    if (!in)
        throw inputError(file.string(), "cannot open " + what,
                         withFix(fix, "check the path and its permissions"));
    std::string bytes;
    char buf[1 << 16];
    while (in) {
        in.read(buf, sizeof buf);
        bytes.append(buf, static_cast<size_t>(in.gcount()));
        if (bytes.size() > maxBytes)
            throw inputError(file.string(),
                             "grew past " + byteCount(maxBytes) + " while it was read as " + what,
                             withFix(fix, "check the path"));
    }
    if (in.bad())
        throw inputError(file.string(), "cannot read " + what,
                         withFix(fix, "check the path and its permissions"));
    return bytes;
}

int jsonNestingDepth(std::string_view text, int limit) {
    int depth = 0, deepest = 0;
    bool inString = false, escaped = false;
    for (const char c : text) {
        if (inString) {
            if (escaped)
                escaped = false;
            else if (c == '\\')
                escaped = true;
            else if (c == '"')
                inString = false;
            continue;
        }
        if (c == '"') {
            inString = true;
        } else if (c == '[' || c == '{') {
            if (++depth > deepest) deepest = depth;
            if (deepest > limit) return limit + 1;
        } else if (c == ']' || c == '}') {
            --depth;
        }
    }
    return deepest;
}

json parseJsonInput(std::string_view text, const std::string& where, const std::string& fix) {
    if (text.size() > kMaxJsonFileBytes)
        throw inputError(where,
                         "is " + std::to_string(text.size()) + " bytes of JSON, more than the " +
                             byteCount(kMaxJsonFileBytes) + " read",
                         fix);
    if (jsonNestingDepth(text) > kMaxJsonDepth)
        throw inputError(where,
                         "JSON nested deeper than " + std::to_string(kMaxJsonDepth) +
                             " levels of arrays and objects is not read",
                         withFix(fix, "check the file (ours nest a few levels)"));
    try {
        return json::parse(text);
    } catch (const json::exception& e) {  // parse_error, or out_of_range for a number like 1e999
        throw inputError(where, std::string("not valid JSON: ") + e.what(),
                         withFix(fix, "fix the syntax (a JSON validator shows the spot)"));
    }
}

json readJsonInput(const fs::path& file, const std::string& what, const std::string& fix) {
    return parseJsonInput(readInputFile(file, what, kMaxJsonFileBytes, fix), file.string(), fix);
}

std::string jsonExcerpt(const json& v, size_t maxChars) {
    std::string out;
    appendExcerpt(v, out, maxChars);
    if (out.size() > maxChars) {
        out.resize(maxChars);
        out += "...";
    }
    return out;
}

bool sameFile(const fs::path& a, const fs::path& b) {
    std::error_code ec;
    if (fs::exists(a, ec) && fs::exists(b, ec)) {
        const bool same = fs::equivalent(a, b, ec);
        if (!ec) return same;
    }
    const fs::path ca = fs::weakly_canonical(a, ec);
    if (ec) return false;
    const fs::path cb = fs::weakly_canonical(b, ec);
    return !ec && ca == cb;
}

bool insideDirectory(const fs::path& file, const fs::path& dir) {
    std::error_code ec;
    const fs::path f = fs::weakly_canonical(file, ec);
    if (ec) return false;
    fs::path d = fs::weakly_canonical(dir, ec);
    if (ec) return false;
    if (!d.has_filename()) d = d.parent_path();
    auto fi = f.begin();
    for (auto di = d.begin(); di != d.end(); ++di, ++fi)
        if (fi == f.end() || *fi != *di) return false;
    return true;
}

void refuseOutputOverInput(const fs::path& output, const std::string& what,
                           const std::vector<fs::path>& inputs, bool directory) {
    if (output.empty()) return;
    for (const fs::path& in : inputs) {
        std::error_code ec;
        if (in.empty() || !fs::exists(in, ec)) continue;  // not a file (a preset's name): no loss
        if (sameFile(output, in))
            throw inputError(what + " " + output.string(),
                             "is an input of this run (" + in.string() +
                                 "); writing it would replace that input",
                             "choose another output name");
        if (directory && insideDirectory(in, output))
            throw inputError(
                what + " " + output.string(),
                "holds an input of this run (" + in.string() + "); it is replaced as a whole",
                "choose another output directory, or move the input out of it");
    }
}

std::string textExcerpt(std::string_view s, size_t maxChars) {
    static const char* hex = "0123456789abcdef";
    std::string out;
    for (const char ch : s) {
        if (out.size() >= maxChars) return out + "...";
        const auto c = static_cast<unsigned char>(ch);
        if (c >= 0x20 && c < 0x7f) {
            out += ch;
        } else {
            out += "\\x";
            out += hex[c >> 4];
            out += hex[c & 15];
        }
    }
    return out;
}

}  // namespace sl
