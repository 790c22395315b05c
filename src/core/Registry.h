// Typed registries: one table per kind of choice (optimizer method, objective, initial state,
// held-out estimate, loss mask), each row {value (an enum), name, help, ...what the kind needs}.
// The table is the only list of the choices: names are parsed into the enum once (the command
// line does it for its flags), `--help` texts and error messages list the table, and code
// switches on the enum (so the compiler finds every place a new entry must be handled). Adding
// a choice is one row plus its code. The shape follows Ceres' types.h/types.cc (enums with one
// string table), with the rows kept as data so other columns ride along.
#pragma once

#include <span>
#include <string>
#include <string_view>

#include "core/Error.h"

namespace sl {

/// The row of `value`. Every enum value has a row (tests/test_registry.cpp checks each table).
template <class Row>
const Row& registryRow(std::span<const Row> table, decltype(Row::value) value) {
    for (const Row& r : table)
        if (r.value == value) return r;
    throw std::logic_error("registry: a value without a row");
}

/// The row named `name`, or nullptr.
template <class Row>
const Row* findRegistryRow(std::span<const Row> table, std::string_view name) {
    for (const Row& r : table)
        if (name == r.name) return &r;
    return nullptr;
}

/// "a, b, c": the names of the table, in its order.
template <class Row>
std::string registryNames(std::span<const Row> table, std::string_view separator = ", ") {
    std::string s;
    for (const Row& r : table) {
        if (!s.empty()) s += separator;
        s += r.name;
    }
    return s;
}

/// The row named `name`; an InputError naming `where` and listing the table otherwise.
template <class Row>
const Row& parseRegistryName(std::span<const Row> table, std::string_view name,
                             const std::string& where) {
    if (const Row* r = findRegistryRow(table, name)) return *r;
    throw inputError(where, "unknown name '" + std::string(name) + "'",
                     "use one of: " + registryNames(table));
}

}  // namespace sl
