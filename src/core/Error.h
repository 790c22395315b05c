// Error types. Every error that the user can fix names the file and/or field and
// says how to fix it; the CLI maps InputError to exit code 1 with that message.
#pragma once

#include <stdexcept>
#include <string>

namespace sl {

/// Bad user input (file, field, value). `what()` is the full message for the user.
class InputError : public std::runtime_error {
  public:
    using std::runtime_error::runtime_error;
};

/// How the library names one of its options in a message: "option 'NAME'" (NAME in the
/// lower-case, dash-separated form of the options struct's field). The library never names a
/// command-line flag; the command line shows "option 'NAME'" as its flag --NAME where it has
/// one (cli/Common.h withFlags).
inline std::string option(const std::string& name) {
    return "option '" + name + "'";
}

/// Builds "<where>: <problem>. <fix>" in one place so messages are uniform.
inline InputError inputError(const std::string& where, const std::string& problem,
                             const std::string& fix = {}) {
    std::string msg = where.empty() ? problem : where + ": " + problem;
    if (!fix.empty()) msg += ". " + fix;
    return InputError(msg);
}

}  // namespace sl
