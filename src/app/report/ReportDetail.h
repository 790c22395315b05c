// The report wing's helpers shared by its two pages (private to src/app/report/): Report.cpp
// (the figures page, `report` and `judge`) and OptimizeReport.cpp (optimize's own page).
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace sl::report {

// Table: one row per key (union over runs), one column per run.
std::string table(const std::vector<std::string>& columns,
                  const std::vector<nlohmann::json>& objects, const std::string& cls);

}  // namespace sl::report
